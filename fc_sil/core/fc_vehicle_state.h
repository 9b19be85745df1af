/*
 * fc_vehicle_state.h - the vehicle as the controllers see it: the one struct
 * between estimation and control (as PX4's vehicle_attitude/local_position
 * topics and Crazyflie's state_t sit between its estimators and controllers).
 *
 * An estimator source (fc_state_source.h) fills it; the attitude, rate and
 * altitude loops (fc_control.h) read attitude, rates and the vertical channel
 * from it and from nowhere else, so what feeds the controllers (the estimate,
 * ground truth, or a blend of both) is decided in one place.
 *
 * The attitude is a weighted pair: the estimate q_wxyz and ground truth
 * q_truth_wxyz with weight truth_w. The paper (3.7) blends the attitude
 * errors, e = (1 - w) e_est + w e_truth, not the quaternions, so the attitude
 * error against a target is defined here, on the state, by
 * fc_vehicle_att_error*; with truth_w = 0 it is the estimate's error exactly.
 * The vertical channel arrives already blended.
 */
#ifndef FC_VEHICLE_STATE_H
#define FC_VEHICLE_STATE_H

#include <stdbool.h>

typedef struct fc_vehicle_state {
    /* Refreshed at each rate-loop step. */
    float q_wxyz[4];          /* estimated attitude, body FRD -> NED */
    float euler_rad[3];       /* roll, pitch, yaw of q_wxyz [rad] */
    float rate_frd_rad_s[3];  /* filtered, bias-corrected body rates [rad/s] */
    float q_truth_wxyz[4];    /* ground-truth attitude, body FRD -> NED */
    float truth_w;            /* weight of ground truth in attitude errors, 0..1 */
    /* Refreshed at each PWM tick. */
    float alt_m;              /* altitude above home, up, blended [m] */
    float climb_m_s;          /* climb rate, up, blended [m/s] */
    float accel_up_m_s2;      /* vertical acceleration, up, of the estimate [m/s^2] */
    float cos_tilt;           /* cosine of the tilt of the latest estimate [1] */
} fc_vehicle_state_t;

/* All zero, attitudes identity. */
void fc_vehicle_state_reset(fc_vehicle_state_t *vs);

/* Small-angle error of an Euler target relative to the state's attitude, body
 * FRD [rad] (fc_attitude_error on each attitude, blended by truth_w). */
void fc_vehicle_att_error(const fc_vehicle_state_t *vs, float roll_target_rad,
                          float pitch_target_rad, float yaw_target_rad, bool hold_yaw,
                          float err_frd_rad[3]);

/* The same against a target quaternion; q_err is the estimate's (target frame
 * to body frame), as the feed-forward rotation needs the body the gyro sees. */
void fc_vehicle_att_error_q(const fc_vehicle_state_t *vs, const float q_target_wxyz[4],
                            float q_err_wxyz[4], float err_frd_rad[3]);

#endif /* FC_VEHICLE_STATE_H */
