/*
 * fc_core.h - the flight-controller chain, stepped once per IMU sample and
 * once per PWM period. This is the one object a host drives (the Python
 * extension here; a real flight controller's scheduler later).
 *
 *   IMU sample : front-end filters -> Mahony -> vertical prediction; then,
 *                decimated to at most SB_LOOP_HZ: the state source publishes
 *                attitude and rates into the vehicle state (the estimate,
 *                blended with ground truth when SB_ATT_SRC asks) -> the rate-loop
 *                step of the control law (input shaping, attitude P + target-rate
 *                feed-forward, rate PI+D x3, hover trim -> mixer inputs cr, cp, cy).
 *   PWM period : spool logic (arming, take-off) -> the state source publishes
 *                the vertical channel -> lift-off and landing detection ->
 *                altitude controller -> mixer, clamp, slew -> PWM, and a status
 *                snapshot.
 *   BARO / MAG / GT / GNSS: routed to the vertical estimator, the heading
 *                corrector, the state source's truth store and a store; while
 *                armed, each GNSS fix is also compared with the IMU history over
 *                its delayed interval (fc_gnss_aid.h) and the result corrects the
 *                estimator's tilt (SB_AHRS_GPS).
 *
 * Estimation and control meet only in the vehicle state (fc_vehicle_state.h):
 * estimators and ground truth fill it (fc_state_source.h), the controllers
 * (fc_control.h, fc_spool.h) read it. Parameters reach the blocks through
 * fc_config_map.h.
 *
 * PWM ticks lie on a grid of 1/SB_PWM_HZ in simulation time. fc_core_pwm_due
 * tells the host when a tick is due: every tick whose time is <= the latest
 * accepted IMU sample. The core keeps no clock of its own and makes no OS call.
 *
 * Inputs (targets) are set between steps with the fc_core_set_* functions
 * (fc_core_inputs.c); they validate (non-finite refused) and take effect on
 * the next step. No heap, no globals: everything lives in fc_core_t (about
 * 4 kB, 1.5 kB of it the GNSS-aiding history).
 */
#ifndef FC_CORE_H
#define FC_CORE_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_alt_est.h"
#include "fc_config_map.h"
#include "fc_control.h"
#include "fc_esc.h"
#include "fc_fft.h"
#include "fc_gnss_aid.h"
#include "fc_inputs.h"
#include "fc_ins.h"
#include "fc_mahony.h"
#include "fc_mixer.h"
#include "fc_params.h"
#include "fc_spool.h"
#include "fc_state_source.h"
#include "fc_status.h"
#include "fc_vehicle_state.h"
#include "fc_vibe.h"

/* One snapshot per PWM tick: what logs, PID_TUNING and tests read. The
 * Python STATUS_DTYPE mirrors this layout field for field (checked by a test). */
typedef struct fc_core_status {
    int64_t sim_ns;                  /* PWM tick time [ns] */
    int64_t imu_sim_ns;              /* latest IMU sample used [ns] */
    float q_est_wxyz[4];             /* estimated attitude, body FRD -> NED */
    float euler_est_rad[3];          /* roll, pitch, yaw of the estimate [rad] */
    float att_target_rad[3];         /* target roll, pitch, yaw: the shaped target [rad] */
    float att_error_frd_rad[3];      /* blended small-angle error ex, ey, ez [rad] */
    float rate_target_frd_rad_s[3];  /* rate-loop targets [rad/s] */
    float rate_frd_rad_s[3];         /* filtered, bias-corrected gyro of the rate loop [rad/s] */
    float pid_p[3];                  /* rate-loop terms per axis [us] */
    float pid_i[3];
    float pid_d[3];
    float pid_ff[3];
    float cp_us, cr_us, cy_us;       /* mixer inputs about 0 [us] (trim included) */
    float throttle_us;               /* mixer throttle input [us] */
    float motor_us[4];               /* mixed and clamped, before the slew limit [us] */
    float trust;                     /* accelerometer trust 0..1 */
    float gyro_bias_rad_s[3];        /* gyro bias estimate [rad/s] */
    float blend_w;                   /* ground-truth weight 0..1 */
    float alt_est_m;                 /* estimated altitude above home, up [m] */
    float climb_est_m_s;             /* estimated climb rate, up [m/s] */
    float alt_target_m;              /* altitude target [m] (NaN when not in altitude mode) */
    float climb_target_m_s;          /* climb-rate target of the altitude loop [m/s] */
    float throttle;                  /* altitude-loop output 0..1 */
    float trim_us[2];                /* applied hover trim, roll and pitch [us] */
    uint32_t loop_count;             /* rate-loop runs so far */
    uint32_t rejected_count;         /* refused input samples so far */
    uint16_t pwm_us[4];              /* outputs after slew [us] */
    uint8_t limited[3];              /* rate-loop integrator limited, per axis */
    uint8_t sat_flags;               /* FC_SAT_* of this tick */
    uint8_t armed;
    uint8_t airborne;                /* lift-off detected and not landed */
    uint8_t spool;                   /* fc_spool_t */
    uint8_t reserved[5];             /* explicit padding to a multiple of 8 */
} fc_core_status_t;

typedef struct fc_gnss_store {
    int64_t sim_ns;
    int32_t lat_e7, lon_e7, alt_mm;
    float vel_ned_m_s[3];
    uint16_t eph_cm;         /* reported horizontal accuracy [cm] (failsafe test ratios) */
    uint16_t epv_cm;         /* reported vertical accuracy [cm] */
    uint8_t fix_type;
    uint8_t satellites;
    bool valid;
} fc_gnss_store_t;

typedef struct fc_core {
    fc_params_t params;
    fc_core_inputs_t in;

    fc_core_config_t cfg;     /* block configurations derived from params (fc_config_map.h) */
    int64_t pwm_period_ns;    /* PWM tick period (SB_PWM_HZ) [ns] */

    /* estimation */
    fc_ins_t ins;
    fc_mahony_t ahrs;
    bool ahrs_ground;         /* ahrs runs the ground configuration */
    fc_alt_est_t alt_est;
    fc_alt_sched_t alt_sched; /* its time constant, by flight phase and innovation */
    fc_gnss_aid_t gnss_aid;   /* IMU history for the GNSS-aided tilt correction */
    uint32_t gnss_aid_count;  /* GNSS fixes that corrected the tilt so far */
    fc_gnss_store_t gnss;
    fc_vibe_t vibe;           /* accel vibration levels and clipping (VIBRATION), per sample */
    fc_esc_t esc;             /* latest ESC telemetry per motor (a store, no control effect) */
    fc_fft_config_t fft_cfg;  /* the in-flight FFT's configuration (FFT_*, fc_fft_params.c) */
    fc_fft_t fft;             /* in-flight gyro FFT: a share per IMU sample; feeds notch MODE 4 */
    fc_state_source_t source; /* estimate + ground truth -> state */
    fc_vehicle_state_t state; /* what the controllers read */

    /* control: the control law (its configuration is cfg.ctl), then the mixer */
    fc_control_state_t ctl;
    fc_control_in_t ctl_in;   /* refreshed from the fields here before each of its steps */
    fc_control_out_t ctl_out; /* its latest results: mixer inputs and what the status reports */
    fc_mixer_t mixer;
    uint8_t spool;            /* fc_spool_t, moved by spool_logic */
    fc_spool_logic_t spool_logic;

    /* time */
    bool have_imu;
    int64_t last_imu_ns;
    float imu_dt_s;           /* IMU period the front-end coefficients use [s] */
    float loop_accum_s;       /* time since the last rate-loop run [s] */
    int64_t next_pwm_ns;

    uint32_t imu_count, loop_count, pwm_count, rejected_count;
    fc_core_status_t status;
} fc_core_t;

/* Defaults for every parameter, all state reset. */
void fc_core_init(fc_core_t *c);
/* Reset all state and inputs, keep parameters. */
void fc_core_reset(fc_core_t *c);

/* Parameters by permanent index: validated (range, finiteness, integrality,
 * cross-checks such as MOT_PWM_MIN < MOT_PWM_MAX), effective at once. */
fc_status_t fc_core_set_param(fc_core_t *c, uint16_t index, float value);
fc_status_t fc_core_get_param(const fc_core_t *c, uint16_t index, float *value);
/* Re-derive every block configuration from c->params (states kept). */
void fc_core_apply_params(fc_core_t *c);

/* Inputs. */
void fc_core_set_armed(fc_core_t *c, bool armed);
fc_status_t fc_core_set_attitude_target(fc_core_t *c, float roll_rad, float pitch_rad);
fc_status_t fc_core_set_yaw_target(fc_core_t *c, float yaw_rad);
fc_status_t fc_core_set_yaw_rate_target(fc_core_t *c, float yaw_rate_rad_s);
fc_status_t fc_core_set_altitude_target(fc_core_t *c, float alt_m);
fc_status_t fc_core_set_climb_target(fc_core_t *c, float climb_m_s);
fc_status_t fc_core_set_throttle(fc_core_t *c, float throttle);
/* The vibration failsafe's switch: the altitude loop's vibration-resistant law (fc_alt_ctrl.h). */
void fc_core_set_vibe_comp(fc_core_t *c, bool on);
/* Optional kinematic acceleration reference for the estimator, NED [m/s^2]
 * (e.g. from GNSS velocity); see fc_mahony.h. Expires after 0.5 s. */
fc_status_t fc_core_set_accel_ref(fc_core_t *c, const float accel_ned_m_s2[3]);

/* Sensor and truth inputs. */
fc_status_t fc_core_imu_step(fc_core_t *c, int64_t sim_ns, const float accel_frd_m_s2[3],
                             const float gyro_frd_rad_s[3]);
fc_status_t fc_core_baro_step(fc_core_t *c, int64_t sim_ns, float pressure_pa);
fc_status_t fc_core_mag_step(fc_core_t *c, int64_t sim_ns, const float field_frd[3]);
fc_status_t fc_core_gt_att_step(fc_core_t *c, int64_t sim_ns, const float q_wxyz[4]);
/* Ground-truth position relative to home and velocity, NED (float: the host
 * converts, so the core has no double arithmetic). */
fc_status_t fc_core_gt_nav_step(fc_core_t *c, int64_t sim_ns, const float pos_ned_m[3],
                                const float vel_ned_m_s[3]);
fc_status_t fc_core_gnss_step(fc_core_t *c, const fc_gnss_store_t *fix);
/* One ESC's telemetry report (fc_esc.h): stored for telemetry, never used by control. */
fc_status_t fc_core_esc_step(fc_core_t *c, int64_t sim_ns, unsigned motor, unsigned motor_count,
                             const float values[5]);

/* System identification (fc_sysid.h): start a SID_* sweep at the next rate-loop
 * step (FC_ERR_ARG when SID_AXIS is 0 or the sweep parameters cannot run), or
 * stop it. The sweep also stops by itself at its end, on disarming and when
 * the tilt exceeds ANGLE_MAX, as ArduCopter's SYSTEMID mode does. */
fc_status_t fc_core_sysid_start(fc_core_t *c);
void fc_core_sysid_stop(fc_core_t *c);

/* PWM: is a tick due (time <= latest IMU)? Then step it; fills c->status. */
bool fc_core_pwm_due(const fc_core_t *c, int64_t *tick_ns);
fc_status_t fc_core_pwm_step(fc_core_t *c, int64_t tick_ns, uint16_t pwm_us[FC_MIXER_MOTORS]);

#endif /* FC_CORE_H */
