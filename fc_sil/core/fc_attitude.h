/*
 * fc_attitude.h - attitude P (paper 3.5): small-angle attitude errors to
 * body-rate references.
 *
 * The error is the rotation vector of q_err = conj(q_est) * q_target (the
 * rotation that takes the estimate to the target, in body FRD; for small
 * angles 2 vec(q_err)): ex, ey are the paper's roll and pitch errors. When yaw is not held
 * (rate mode, or ATC_ANG_YAW_P = 0 as in the paper) the target keeps the
 * estimate's own heading, so ez = 0 and the yaw rate target is just the
 * commanded yaw rate: rate damping.
 */
#ifndef FC_ATTITUDE_H
#define FC_ATTITUDE_H

#include <stdbool.h>

typedef struct fc_attitude_config {
    float ang_p[3];          /* rate target per rad of error, roll/pitch/yaw [1/s] */
    float rate_max_rad_s[3]; /* rate target limit; 0 = none [rad/s] */
} fc_attitude_config_t;

/* Small-angle error (target relative to estimate), body FRD [rad]. With
 * hold_yaw false, yaw_target_rad is ignored and the estimate's yaw is used. */
void fc_attitude_error(const float q_est_wxyz[4], float roll_target_rad, float pitch_target_rad,
                       float yaw_target_rad, bool hold_yaw, float err_frd_rad[3]);

/* Body-rate targets [rad/s] from the error, plus a yaw rate feed-forward. */
void fc_attitude_rate_targets(const fc_attitude_config_t *cfg, const float err_frd_rad[3],
                              float yaw_rate_ff_rad_s, float rate_target_frd_rad_s[3]);

#endif /* FC_ATTITUDE_H */
