/*
 * fc_mahony.h - Mahony attitude estimator (paper Listing 3, corrected).
 *
 * Per IMU sample: the accelerometer direction is compared with the gravity
 * direction the estimate predicts; the cross product is the tilt error. A PI
 * correction, weighted by an accelerometer trust, is added to the
 * bias-corrected gyro rate, and the quaternion is integrated with the
 * exponential map and renormalised.
 *
 * Accelerometer trust: trust_raw = clamp(1 - | |a|/g - 1 | / span, 0, 1) (the
 * listing has span = 1 g; a smaller span distrusts dynamic flight sooner), smoothed by
 * an EMA of time constant trust_tc_s (alpha = 1 - exp(-dt/tau), so the
 * smoothing does not depend on the IMU rate). Two fixes against the listing:
 * its trust lived in a function-local `static` (a global in disguise: two
 * estimators would share it); ours is in the struct. And it took |a| of the
 * already normalised vector, so trust_raw was always 1; we use the raw |a|.
 *
 * Gyro bias: the listing's EMA `bias = (1-b) bias + b (gyro - omega)` feeds
 * back omega, which already contains -bias and the correction terms, and
 * uses a per-sample b (so its time constant changes with the IMU rate). What
 * observes the bias is the PI integrator: in steady state integ = bias -
 * true_bias. So under quasi-static conditions (|gyro - bias| and | |a|/g - 1 |
 * small) we move a fraction alpha = 1 - exp(-dt * bias_rate) of the
 * integrator into the explicit bias estimate (bias -= alpha integ; integ -=
 * alpha integ). omega is unchanged by the transfer (bumpless), and the bias
 * estimate is what logs and tests read.
 *
 * Acceleration reference (optional): without one, the accelerometer is taken
 * to measure gravity alone, which a sustained horizontal acceleration (a held
 * tilt, a steady push) violates for seconds: the estimate is pulled towards
 * the thrust axis. A host that knows the vehicle's kinematic acceleration
 * (from GNSS velocity, say) can hand it in with fc_mahony_set_accel_ref; the
 * expected specific force then becomes a_ref - g and the trust compares |a|
 * with its magnitude. It expires FC_MAHONY_ACCEL_REF_STALE_S after the last set.
 *
 * GNSS-aided tilt (fc_mahony_gnss; fc_gnss_aid.h computes its inputs): the
 * mean specific force over a past fix interval, measured (IMU rotated by the
 * estimate) and implied by GNSS velocity, both NED. Their cross product is
 * the estimate's tilt error at that time, free of the vehicle's acceleration
 * and of the GNSS latency. Its horizontal part (the vertical one is heading,
 * which the magnetometer owns) is held until the next fix and, while fresh,
 * replaces the accelerometer tilt error: P gain kp_gnss, I gain ki_gnss. The
 * integrator then learns a gyro bias in flight, where the accelerometer alone
 * cannot tell a bias-driven tilt from the thrust axis. kp_gnss and ki_gnss are
 * the quiet (hover) gains; while the low-passed error stands out of its noise,
 * their bandwidth rises up to gnss_boost times (fc_sched.h: fc_aid_sched).
 *
 * Heading offset: GNSS velocity is relative to true north, the magnetometer to
 * magnetic north; a wrong COMPASS_DEC (set by hand, or with COMPASS_AUTODEC 0;
 * otherwise the host sets it from a WMM table as ArduPilot does) turns the
 * estimate's heading, and with a horizontal
 * acceleration that heading error tilts the GNSS reference (by tan(tilt) of
 * itself: 2.6 deg at 30 deg for the 4.5 deg of a zero COMPASS_DEC at Zurich).
 * When the acceleration changes direction, the down component of the
 * GNSS-aided error carries that heading error; it is integrated slowly into
 * heading_offset_rad, which the magnetometer correction then subtracts. A
 * steady acceleration or hover leaves the offset alone (the component is ~0).
 *
 * Heading (paper 3.4: MAG goes to the yaw/heading corrector): each
 * magnetometer sample gives the heading error of the estimate (field rotated
 * to NED, its horizontal direction against magnetic north + declination); it
 * is applied about the NED down axis with gain kmag and integrated with ki,
 * which makes the yaw gyro bias observable. The first sample after alignment
 * sets the heading at once.
 */
#ifndef FC_MAHONY_H
#define FC_MAHONY_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_sched.h"
#include "fc_status.h"

typedef struct fc_mahony_config {
    float kp;               /* tilt correction P [1/s] */
    float ki;               /* tilt correction I [1/s^2] */
    float kmag;             /* heading correction P [1/s] */
    float trust_tc_s;       /* accelerometer-trust EMA time constant [s] */
    float trust_span_g;     /* | |a|/g - 1 | at which the raw trust reaches 0 [g] */
    float bias_rate_hz;     /* integrator -> bias transfer rate while quasi-static [1/s] */
    float still_gyro_rad_s; /* quasi-static: |gyro - bias| below this [rad/s] */
    float still_acc_g;      /* quasi-static: | |a|/g - 1 | below this [g] */
    float kp_gnss;          /* GNSS-aided tilt correction P [1/s] */
    float ki_gnss;          /* GNSS-aided tilt correction I [1/s^2] */
    float gnss_boost;       /* largest bandwidth factor on them (fc_sched.h); <= 1: none */
    float gnss_innov_sigma; /* boost threshold, in noise sigmas of the mean error */
    bool trust_ema_enable;  /* false: trust = trust_raw (ablation) */
    bool bias_enable;       /* false: no explicit bias estimate */
} fc_mahony_config_t;

typedef struct fc_mahony {
    fc_mahony_config_t cfg;
    float q_wxyz[4];          /* body FRD -> world NED */
    float bias_rad_s[3];      /* gyro bias estimate, FRD [rad/s] */
    float integ_rad_s[3];     /* PI integrator, FRD [rad/s] */
    float trust;              /* smoothed accelerometer trust, 0..1 */
    float trust_raw;          /* this sample's trust, 0..1 */
    float accel_ref_ned_m_s2[3]; /* kinematic acceleration reference, NED [m/s^2] */
    float accel_ref_age_s;    /* time since it was set [s] */
    bool accel_ref_valid;
    float gnss_err_ned_rad[3]; /* latest GNSS-aided tilt error, NED (down part 0) */
    float gnss_age_s;         /* time since it was measured [s] */
    bool gnss_valid;          /* a GNSS-aided error is held */
    float gnss_err_down_rad;  /* down component of that error (heading information) */
    fc_aid_sched_t gnss_sched; /* evidence-scheduled bandwidth of the aided gains */
    float heading_offset_rad; /* magnetic heading offset learned from GNSS [rad] */
    float heading_err_rad;    /* latest magnetometer heading error (estimate - mag) */
    float heading_age_s;      /* time since that error was measured [s] */
    bool heading_valid;       /* a magnetometer sample has been used */
    bool still;               /* quasi-static on the last sample */
    bool aligned;             /* tilt initialised from the accelerometer */
} fc_mahony_t;

void fc_mahony_init(fc_mahony_t *m, const fc_mahony_config_t *cfg);
void fc_mahony_configure(fc_mahony_t *m, const fc_mahony_config_t *cfg);
/* Set the attitude (tests start 30 degrees off); clears bias and integrator. */
void fc_mahony_set_attitude(fc_mahony_t *m, const float q_wxyz[4]);
/* Turn the estimate's heading by delta_rad about NED down (a new declination), keeping
 * bias and integrator: the heading loop would otherwise learn the step as a yaw gyro bias. */
void fc_mahony_turn_heading(fc_mahony_t *m, float delta_rad);
/* Roll and pitch from one accelerometer sample, yaw 0. */
fc_status_t fc_mahony_align(fc_mahony_t *m, const float accel_frd_m_s2[3]);
fc_status_t fc_mahony_update(fc_mahony_t *m, const float gyro_frd_rad_s[3],
                             const float accel_frd_m_s2[3], float dt_s);
fc_status_t fc_mahony_mag(fc_mahony_t *m, const float field_frd[3], float declination_rad);
/* Kinematic acceleration of the vehicle, NED [m/s^2] (not the specific force). */
fc_status_t fc_mahony_set_accel_ref(fc_mahony_t *m, const float accel_ned_m_s2[3]);
/* Mean specific force over one past interval, measured by the IMU (rotated by
 * the estimate) and implied by GNSS velocity, NED [m/s^2]. FC_ERR_ARG (and
 * nothing held) when either is too small to give a direction or they point
 * more than 90 degrees apart. */
fc_status_t fc_mahony_gnss(fc_mahony_t *m, const float f_imu_ned_m_s2[3],
                           const float f_gnss_ned_m_s2[3]);
/* Drop the held GNSS-aided error (aiding off, fix lost): back to the accelerometer. */
void fc_mahony_gnss_forget(fc_mahony_t *m);
/* True while a GNSS-aided error is fresh and replaces the accelerometer's. */
bool fc_mahony_gnss_active(const fc_mahony_t *m);

#endif /* FC_MAHONY_H */
