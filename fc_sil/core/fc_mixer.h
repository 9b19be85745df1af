/*
 * fc_mixer.h - quad-X mixer with saturation flags, yaw headroom, output clamp
 * and per-motor slew limit; PWM 1000..2000 us (paper 3.8).
 *
 * Motor order and spin directions are ArduCopter's QUAD X (seen from above):
 *     motor 1  front-right  CCW      motor 3  front-left  CW
 *     motor 2  back-left    CCW      motor 4  back-right  CW
 *         3   1          roll  +  (right wing down): left motors (2, 3) up
 *          \ /           pitch +  (nose up):         front motors (1, 3) up
 *          / \           yaw   +  (nose right, CW from above): the CCW
 *         2   4                   motors (1, 2) up, whose drag torque on
 *                                 the frame is clockwise
 * so motor_i = throttle + r_i cr + p_i cp + y_i cy with
 *     r = {-1, +1, +1, -1}, p = {+1, -1, +1, -1}, y = {+1, +1, -1, -1}.
 *
 * Inputs are in us: throttle about MOT_PWM_MIN..MAX, cr/cp/cy offsets about 0.
 * Priorities as ArduCopter: roll/pitch first (scaled down together when they
 * need more than the range, around the demanded collective within limits,
 * fc_mixer_sat.h: roll+pitch flags), then yaw (limited to the room
 * left, but never below MOT_YAW_HEADROOM: yaw flag), then throttle gives way
 * (throttle flags). The flags go back to the rate loop (no integrator growth)
 * and the altitude loop.
 */
#ifndef FC_MIXER_H
#define FC_MIXER_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_status.h"

#define FC_MIXER_MOTORS 4

#define FC_SAT_ROLL 0x01u
#define FC_SAT_PITCH 0x02u
#define FC_SAT_YAW 0x04u
#define FC_SAT_THR_HIGH 0x08u
#define FC_SAT_THR_LOW 0x10u

typedef enum fc_spool {
    FC_SPOOL_SHUT_DOWN = 0, /* disarmed: MOT_PWM_MIN on every output */
    FC_SPOOL_GROUND_IDLE = 1, /* armed on the ground: throttle only, no attitude mix */
    FC_SPOOL_FLIGHT = 2     /* full mix within the MOT_SPIN_MIN..MAX band */
} fc_spool_t;

typedef struct fc_mixer_config {
    float pwm_min_us, pwm_max_us;   /* output range [us] */
    float spin_min, spin_max;       /* in-flight band, fractions of the range */
    float yaw_headroom_us;          /* yaw authority always kept [us] */
    float slew_up_time_s;           /* full-range rise time; 0 = no limit [s] */
    float slew_dn_time_s;           /* full-range fall time; 0 = no limit [s] */
    bool slew_enable;
} fc_mixer_config_t;

typedef struct fc_mixer {
    float motor_us[FC_MIXER_MOTORS]; /* mixed and clamped, before the slew limit [us] */
    float out_us[FC_MIXER_MOTORS];   /* after the slew limit: what goes out [us] */
    float roll_us, pitch_us, yaw_us, throttle_us; /* inputs as actually applied [us] */
    uint8_t sat_flags;               /* FC_SAT_* of the last update */
} fc_mixer_t;

extern const float fc_mixer_roll_factor[FC_MIXER_MOTORS];
extern const float fc_mixer_pitch_factor[FC_MIXER_MOTORS];
extern const float fc_mixer_yaw_factor[FC_MIXER_MOTORS];

void fc_mixer_reset(fc_mixer_t *m, const fc_mixer_config_t *cfg);
/* One PWM period. Non-finite inputs are treated as 0 (and FC_ERR_NONFINITE
 * returned); the outputs are always finite and within [pwm_min, pwm_max]. */
fc_status_t fc_mixer_update(fc_mixer_t *m, const fc_mixer_config_t *cfg, int spool,
                            float throttle_us, float roll_us, float pitch_us, float yaw_us,
                            float dt_s, uint16_t pwm_out_us[FC_MIXER_MOTORS]);

/* ArduCopter's motors->get_throttle_out(): the throttle the mixer applied, as a fraction of
 * the PWM range (the unit of MOT_THST_HOVER). The notch's MODE 1 and the FFT's hover learning
 * both read it. */
static inline float fc_mixer_throttle_out(const fc_mixer_t *m, const fc_mixer_config_t *cfg)
{
    const float range_us = cfg->pwm_max_us - cfg->pwm_min_us;
    return (range_us > 0.0f) ? (m->throttle_us - cfg->pwm_min_us) / range_us : 0.0f;
}

#endif /* FC_MIXER_H */
