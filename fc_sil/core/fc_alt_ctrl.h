/*
 * fc_alt_ctrl.h - altitude controller (ArduCopter AC_PosControl z):
 *     altitude error -PSC_POSZ_P-> climb-rate target (limited to
 *     PILOT_SPEED_UP / PILOT_SPEED_DN) -PSC_VELZ_P-> vertical acceleration
 *     target -PSC_ACCZ_P/I (IMAX)-> throttle about MOT_THST_HOVER,
 * then tilt compensation (throttle / cos(tilt), tilt capped at 60 degrees).
 * The acceleration PID works in ArduCopter's units: error in cm/s^2, output in
 * thousandths of throttle. Its integrator may not grow further into a mixer
 * throttle limit. A direct-throttle mode (for STABILIZE) bypasses it all.
 * Vibration compensation (ArduCopter AC_PosControl::get_throttle_with_vibration_override,
 * switched by the vibration failsafe): the measured acceleration is what vibration corrupts,
 * so the acceleration PID is replaced by a feed-forward of the acceleration target
 * (FC_ALT_VIBE_P_GAIN of the hover throttle per g) and an integrator of the climb-rate error
 * (FC_ALT_VIBE_I_GAIN), which keeps the accel integrator's state.
 * Units: up-positive, as fc_alt_est.
 */
#ifndef FC_ALT_CTRL_H
#define FC_ALT_CTRL_H

#include <stdbool.h>

#include "fc_filter.h"

typedef enum fc_alt_mode {
    FC_ALT_MODE_ALTITUDE = 0, /* hold/seek an altitude above home */
    FC_ALT_MODE_CLIMB = 1,    /* follow a climb rate */
    FC_ALT_MODE_THROTTLE = 2  /* direct throttle, 0..1 */
} fc_alt_mode_t;

typedef struct fc_alt_ctrl_config {
    float pos_p;           /* [1/s] */
    float vel_p;           /* [1/s] */
    float acc_p;           /* thousandths of throttle per cm/s^2 */
    float acc_i;           /* thousandths of throttle per cm/s */
    float acc_imax;        /* thousandths of throttle */
    float acc_flte_hz;     /* accel error PT1; 0 = off */
    float speed_up_m_s;    /* climb limit [m/s] */
    float speed_dn_m_s;    /* descent limit [m/s], positive */
    float hover_throttle;  /* feed-forward, 0..1 */
} fc_alt_ctrl_config_t;

typedef struct fc_alt_ctrl {
    fc_pt1_t err_lpf;
    float dt_s;               /* period the error filter was computed for [s] */
    float integ;              /* accel integrator, thousandths of throttle */
    float climb_target_m_s;   /* last climb-rate target, up [m/s] */
    float accel_target_m_s2;  /* last acceleration target, up [m/s^2] */
    float throttle;           /* last output, 0..1 */
    bool primed;
} fc_alt_ctrl_t;

void fc_alt_ctrl_init(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, float dt_s);
void fc_alt_ctrl_configure(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, float dt_s);
void fc_alt_ctrl_reset(fc_alt_ctrl_t *c);
/* One step; returns throttle 0..1. `target` is m (ALTITUDE), m/s (CLIMB) or
 * 0..1 (THROTTLE). limit_up/limit_dn: the mixer clipped throttle high/low. vibe_comp: the
 * vibration-resistant law. */
float fc_alt_ctrl_update(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, int mode,
                         float target, float alt_m, float climb_m_s, float accel_up_m_s2,
                         float cos_tilt, bool limit_up, bool limit_dn, bool vibe_comp,
                         float dt_s);

#endif /* FC_ALT_CTRL_H */
