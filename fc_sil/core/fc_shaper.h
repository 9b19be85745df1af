/*
 * fc_shaper.h - attitude input shaping, as ArduCopter's AC_AttitudeControl
 * (input_euler_angle_roll_pitch_euler_rate_yaw / _roll_pitch_yaw).
 *
 * A commanded attitude is not handed to the attitude P as a raw step. A
 * TARGET attitude moves toward it instead: per Euler axis, a square-root
 * controller gives the angular velocity that brings the target to rest on the
 * command with deceleration ATC_ACCEL_*_MAX, ending in an exponential tail of
 * time constant ATC_INPUT_TC; the change of that velocity per step is also
 * limited by the acceleration, so the target starts smoothly. The target's
 * body-frame angular velocity (limited by ATC_RATE_*_MAX) is fed forward into
 * the rate loop, and the attitude P only corrects what remains, so the vehicle
 * flies the target closely instead of lagging a step by its whole size.
 *
 * Zero limits as in ArduCopter: an acceleration of 0 means no acceleration
 * limit (the target then follows a first-order lag of ATC_INPUT_TC); a rate
 * limit of 0 means none. ATC_INPUT_TC is floored at 10 ms as in ArduCopter;
 * with ATC_INPUT_TC = 0 AND no acceleration limit the axis passes its command
 * straight through with no feed-forward (a step has no finite rate to feed).
 *
 * The yaw target is shaped toward a held heading, or (rate mode) its rate is
 * slewed toward the commanded yaw rate at the yaw acceleration limit.
 * Angles are ZYX Euler (roll, pitch, yaw); body rates FRD.
 */
#ifndef FC_SHAPER_H
#define FC_SHAPER_H

#include <stdbool.h>

typedef struct fc_shaper_config {
    bool enable;                 /* false: targets are the commands, no feed-forward */
    float input_tc_s;            /* ATC_INPUT_TC [s] */
    float accel_max_rad_s2[3];   /* body roll, pitch, yaw acceleration limits; 0 = none [rad/s^2] */
    float rate_max_rad_s[3];     /* body roll, pitch, yaw rate limits; 0 = none [rad/s] */
} fc_shaper_config_t;

typedef struct fc_shaper {
    float euler_rad[3];             /* target roll, pitch, yaw [rad] */
    float euler_rate_rad_s[3];      /* its Euler-angle rates [rad/s] */
    float ang_vel_frd_rad_s[3];     /* its angular velocity, target body frame [rad/s] */
} fc_shaper_t;

/* ArduPilot's sqrt_controller: linear (error * p) near zero, sqrt(2 a |e|)
 * beyond a / p^2, never more than would cross zero within dt. p = 0: pure
 * sqrt; second_ord_lim <= 0: pure linear. */
float fc_sqrt_controller(float error, float p, float second_ord_lim, float dt_s);
/* Step an angular velocity toward desired with |change| <= accel_max * dt (0 = unlimited). */
float fc_shape_ang_vel(float target_ang_vel, float desired_ang_vel, float accel_max, float dt_s);
/* Angular velocity that takes an angle error to zero with limited acceleration. */
float fc_shape_angle(float error_rad, float input_tc_s, float accel_max, float target_ang_vel,
                     float dt_s);

/* ArduCopter's ang_vel_limit: roll and pitch limited together (an ellipse)
 * when both limits are set, else each alone; yaw alone. 0 = no limit. */
void fc_ang_vel_limit(float ang_vel_rad_s[3], const float rate_max_rad_s[3]);
/* Body acceleration limits seen on the Euler axes at an attitude (ArduCopter
 * euler_accel_limit); any limit 0 returns them unchanged. */
void fc_euler_accel_limit(const float euler_rad[3], const float body_accel[3],
                          float euler_accel[3]);
/* ZYX Euler-angle rates <-> body angular velocity at an attitude. */
void fc_euler_rate_to_ang_vel(const float euler_rad[3], const float euler_rate[3],
                              float ang_vel[3]);
void fc_ang_vel_to_euler_rate(const float euler_rad[3], const float ang_vel[3],
                              float euler_rate[3]);

/* Target := the given attitude, at rest (ArduCopter relax_attitude_controllers). */
void fc_shaper_reset(fc_shaper_t *s, const float euler_rad[3]);
/* One step of dt_s: advance the target by its rate, then shape the rates
 * toward the commands. hold_yaw: shape toward yaw_cmd_rad; else slew the yaw
 * rate toward yaw_rate_cmd_rad_s. Disabled: the target is the command and
 * every rate is zero (the yaw target then integrates yaw_rate_cmd_rad_s). */
void fc_shaper_update(fc_shaper_t *s, const fc_shaper_config_t *cfg, float roll_cmd_rad,
                      float pitch_cmd_rad, float yaw_cmd_rad, float yaw_rate_cmd_rad_s,
                      bool hold_yaw, float dt_s);
/* Keep the yaw target on a heading (rate mode follows the vehicle's own). */
void fc_shaper_set_yaw(fc_shaper_t *s, float yaw_rad);
/* The same, and the yaw target at rest (ArduCopter reset_yaw_target_and_rate). */
void fc_shaper_reset_yaw(fc_shaper_t *s, float yaw_rad);

#endif /* FC_SHAPER_H */
