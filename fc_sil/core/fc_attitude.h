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
 *
 * With input shaping on (fc_shaper.h, ATC_RATE_FF_ENAB and SB_SHAPE_EN) the
 * target is the shaped attitude, and fc_attitude_rate_targets_ff adds the
 * target's own angular velocity to the P output, as ArduCopter does.
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

/* The same error against a target quaternion; also returns q_err, the
 * rotation from the target frame to the body frame. */
void fc_attitude_error_q(const float q_est_wxyz[4], const float q_target_wxyz[4],
                         float q_err_wxyz[4], float err_frd_rad[3]);

/* With input shaping (fc_shaper.h), as ArduCopter's attitude_controller_run_quat:
 * P on the error, limited by ATC_RATE_*_MAX, plus the target's angular
 * velocity seen in the body frame (rotated by q_err). While the thrust
 * vectors of target and body differ by more than FC_ATT_THRUST_ERR_RAD the
 * feed-forward fades out, and the yaw target fades to the measured yaw rate
 * (gyro_z_rad_s): the tilt is corrected first. Returns the fade factor 0..1. */
#define FC_ATT_THRUST_ERR_RAD 0.523598776f /* 30 deg, ArduCopter AC_ATTITUDE_THRUST_ERROR_ANGLE */
float fc_attitude_rate_targets_ff(const fc_attitude_config_t *cfg, const float err_frd_rad[3],
                                  const float q_err_wxyz[4], const float ang_vel_target_rad_s[3],
                                  float gyro_z_rad_s, float rate_target_frd_rad_s[3]);

#endif /* FC_ATTITUDE_H */
