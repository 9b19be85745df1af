/*
 * fc_rate_pid.h - one axis of the rate loop: PI + D on measurement (paper 3.6).
 *
 * Gains are ArduCopter's (normalised output: 1.0 = the motor authority of
 * ArduPilot's mixer, i.e. out_us_per_unit microseconds of PWM); outputs and
 * the info struct are in microseconds because the mixer and the paper work in
 * us about 1500.
 *   P  = kp * e,  e = filtered(target) - measurement, optional error PT1 (FLTE)
 *   I  : conditional integration. Only while `integrate` (airborne); clamped
 *        to +-IMAX; while the mixer reports saturation on this axis the
 *        integrator may shrink but not grow (ArduPilot AC_PID rule).
 *   D  = -kd * d(measurement_filtered)/dt: on the measurement, so a target step
 *        gives no D kick; the sign opposes the measured angular acceleration.
 *        The measurement goes through a PT2x2 (paper) or a PT1 (ArduCopter)
 *        at FLTD, then the output is clamped to +-d_clamp_us (paper: 12 us).
 *   FF = kff * target.
 * antiwindup = false (the yaw ablation) drops the saturation rule and widens
 * the integrator limit from IMAX to the full authority (1.0).
 */
#ifndef FC_RATE_PID_H
#define FC_RATE_PID_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_filter.h"

typedef struct fc_rate_pid_config {
    float kp, ki, kd, kff; /* ArduCopter ATC_RAT_* gains (normalised output) */
    float imax;            /* integrator limit (normalised) */
    float fltt_hz;         /* target PT1 cutoff; 0 = off */
    float flte_hz;         /* error PT1 cutoff; 0 = off */
    float fltd_hz;         /* D-term measurement filter cutoff; 0 = off */
    float out_us_per_unit; /* PWM us per normalised unit */
    float d_clamp_us;      /* D output clamp, +- [us] */
    bool d_clamp_enable;
    bool d_pt2x2;          /* true: PT2x2 D filter (paper); false: PT1 (ArduCopter) */
    bool antiwindup;
} fc_rate_pid_config_t;

/* What logs and PID_TUNING read (AP_PIDInfo-like). */
typedef struct fc_pid_info {
    float target_rad_s;   /* filtered rate target */
    float actual_rad_s;   /* measurement */
    float error_rad_s;    /* filtered error */
    float p_us, i_us, d_us, ff_us;
    float out_us;         /* P + I + D + FF */
    uint8_t limited;      /* integrator held by the mixer limit or at its clamp */
    uint8_t d_clamped;    /* the D clamp acted on this step */
} fc_pid_info_t;

typedef struct fc_rate_pid {
    fc_rate_pid_config_t cfg;
    float dt_s;              /* loop period the filters were computed for [s] */
    fc_pt1_t target_lpf;
    fc_pt1_t error_lpf;
    fc_filter_t d_filter;    /* PT2x2 or PT1, chosen at configure */
    float meas_prev;         /* previous filtered measurement [rad/s] */
    float integ;             /* integrator (normalised) */
    bool primed;
    fc_pid_info_t info;
} fc_rate_pid_t;

/* dt_s: the period the filters start with (the nominal loop period). */
void fc_rate_pid_init(fc_rate_pid_t *pid, const fc_rate_pid_config_t *cfg, float dt_s);
/* New gains, cutoffs or loop period; filter states and integrator kept (a
 * change of D filter kind re-primes the D filter at the last measurement).
 * A host that steps at a measured period passes pid->dt_s here and leaves the
 * period to fc_rate_pid_update. */
void fc_rate_pid_configure(fc_rate_pid_t *pid, const fc_rate_pid_config_t *cfg, float dt_s);
/* Clear filters and integrator; the next update primes from its inputs. */
void fc_rate_pid_reset(fc_rate_pid_t *pid);
void fc_rate_pid_reset_integrator(fc_rate_pid_t *pid);
/* One step of dt_s, the period since the previous step [s]: I and D use it,
 * and the filters are recomputed for it when it moves by more than
 * FC_RETUNE_TOLERANCE (fc_math.h) from pid->dt_s, so the period enters the PID
 * through this one argument. Returns out_us (also in pid->info). A non-finite
 * target or measurement returns the previous output and updates nothing but
 * the filter period. */
float fc_rate_pid_update(fc_rate_pid_t *pid, float target_rad_s, float meas_rad_s, float dt_s,
                         bool mixer_limit, bool integrate);

#endif /* FC_RATE_PID_H */
