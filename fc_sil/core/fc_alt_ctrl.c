/*
 * fc_alt_ctrl.c - altitude controller (see fc_alt_ctrl.h).
 */
#include "fc_alt_ctrl.h"

#include "fc_math.h"

#define FC_ALT_MIN_COS_TILT 0.5f /* tilt compensation stops growing beyond 60 deg */
#define FC_ALT_VIBE_P_GAIN 0.250f  /* POSCONTROL_VIBE_COMP_P_GAIN (AC_PosControl) */
#define FC_ALT_VIBE_I_GAIN 0.125f  /* POSCONTROL_VIBE_COMP_I_GAIN */

void fc_alt_ctrl_configure(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, float dt_s)
{
    fc_pt1_update_cutoff(&c->err_lpf, cfg->acc_flte_hz, dt_s);
    c->dt_s = dt_s;
}

void fc_alt_ctrl_reset(fc_alt_ctrl_t *c)
{
    fc_pt1_reset(&c->err_lpf, 0.0f);
    c->integ = 0.0f;
    c->climb_target_m_s = 0.0f;
    c->accel_target_m_s2 = 0.0f;
    c->throttle = 0.0f;
    c->primed = false;
}

void fc_alt_ctrl_init(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, float dt_s)
{
    c->err_lpf.k = 1.0f;
    fc_alt_ctrl_configure(c, cfg, dt_s);
    fc_alt_ctrl_reset(c);
}

/* The vibration override: throttle per cm/s^2 of acceleration is the hover throttle per g; the
 * integrator grows with the climb-rate error unless the mixer clips, when it may only shrink. */
static float vibe_throttle(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, float vel_err_m_s,
                           float accel_target_m_s2, bool limited, float dt_s)
{
    const float thr_per_cmss = cfg->hover_throttle / (FC_GRAVITY_M_S2 * 100.0f);
    if (!limited || (c->integ > 0.0f && vel_err_m_s < 0.0f)
        || (c->integ < 0.0f && vel_err_m_s > 0.0f)) {
        c->integ += dt_s * thr_per_cmss * 1000.0f * (100.0f * vel_err_m_s) * cfg->vel_p
                    * FC_ALT_VIBE_I_GAIN;
    }
    c->integ = fc_constrainf(c->integ, -cfg->acc_imax, cfg->acc_imax);
    return cfg->hover_throttle
           + FC_ALT_VIBE_P_GAIN * thr_per_cmss * (100.0f * accel_target_m_s2) + 0.001f * c->integ;
}

float fc_alt_ctrl_update(fc_alt_ctrl_t *c, const fc_alt_ctrl_config_t *cfg, int mode,
                         float target, float alt_m, float climb_m_s, float accel_up_m_s2,
                         float cos_tilt, bool limit_up, bool limit_dn, bool vibe_comp,
                         float dt_s)
{
    if (!fc_finitef(target) || !fc_finitef(alt_m) || !fc_finitef(climb_m_s)
        || !fc_finitef(accel_up_m_s2) || !(dt_s > 0.0f)) {
        return c->throttle;
    }
    if (mode == FC_ALT_MODE_THROTTLE) {
        c->throttle = fc_constrainf(target, 0.0f, 1.0f);
        c->climb_target_m_s = 0.0f;
        c->accel_target_m_s2 = 0.0f;
        c->primed = false;
        return c->throttle;
    }
    float climb_target = (mode == FC_ALT_MODE_CLIMB) ? target : cfg->pos_p * (target - alt_m);
    climb_target = fc_constrainf(climb_target, -cfg->speed_dn_m_s, cfg->speed_up_m_s);
    const float accel_target = cfg->vel_p * (climb_target - climb_m_s);

    if (vibe_comp) {
        const float thr_v = vibe_throttle(c, cfg, climb_target - climb_m_s, accel_target,
                                          limit_up || limit_dn, dt_s);
        const float boost_v = fmaxf(fc_finitef(cos_tilt) ? cos_tilt : 1.0f, FC_ALT_MIN_COS_TILT);
        c->primed = false;
        c->climb_target_m_s = climb_target;
        c->accel_target_m_s2 = accel_target;
        c->throttle = fc_constrainf(thr_v / boost_v, 0.0f, 1.0f);
        return c->throttle;
    }
    const float err_cmss_raw = 100.0f * (accel_target - accel_up_m_s2);
    if (!c->primed) {
        fc_pt1_reset(&c->err_lpf, err_cmss_raw);
        c->primed = true;
    }
    const float err_cmss = fc_pt1_apply(&c->err_lpf, err_cmss_raw);
    const float candidate = c->integ + cfg->acc_i * err_cmss * dt_s;
    /* No further growth into a throttle limit the mixer reported. */
    if (!((limit_up && candidate > c->integ) || (limit_dn && candidate < c->integ))) {
        c->integ = candidate;
    }
    c->integ = fc_constrainf(c->integ, -cfg->acc_imax, cfg->acc_imax);
    const float thr = cfg->hover_throttle + 0.001f * (cfg->acc_p * err_cmss + c->integ);
    const float boost = fmaxf(fc_finitef(cos_tilt) ? cos_tilt : 1.0f, FC_ALT_MIN_COS_TILT);

    c->climb_target_m_s = climb_target;
    c->accel_target_m_s2 = accel_target;
    c->throttle = fc_constrainf(thr / boost, 0.0f, 1.0f);
    return c->throttle;
}
