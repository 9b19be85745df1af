/*
 * fc_trim.c - hover-trim learning with ramp-in (see fc_trim.h).
 */
#include "fc_trim.h"

#include "fc_math.h"

void fc_trim_reset(fc_trim_t *t)
{
    t->phase = FC_TRIM_WAITING;
    t->elapsed_s = 0.0f;
    for (int i = 0; i < 2; i++) {
        t->err_sum_rad_s[i] = 0.0f;
        t->learned_us[i] = 0.0f;
        t->applied_us[i] = 0.0f;
    }
}

void fc_trim_update(fc_trim_t *t, const fc_trim_config_t *cfg, bool airborne, float ex_rad,
                    float ey_rad, float dt_s, float out_us[2])
{
    const bool ok = cfg->enable && fc_finitef(ex_rad) && fc_finitef(ey_rad) && dt_s > 0.0f
                    && fc_finitef(dt_s);
    if (!cfg->enable) {
        fc_trim_reset(t);
    } else if (ok) {
        switch (t->phase) {
        case FC_TRIM_WAITING:
            if (airborne) {
                t->phase = FC_TRIM_LEARNING;
                t->elapsed_s = 0.0f;
            }
            break;
        case FC_TRIM_LEARNING:
            t->err_sum_rad_s[0] += ex_rad * dt_s;
            t->err_sum_rad_s[1] += ey_rad * dt_s;
            t->elapsed_s += dt_s;
            if (t->elapsed_s >= cfg->window_s) {
                for (int i = 0; i < 2; i++) {
                    const float mean = t->err_sum_rad_s[i] / t->elapsed_s;
                    t->learned_us[i] =
                        fc_constrainf(cfg->gain_us_per_rad * mean, -cfg->max_us, cfg->max_us);
                }
                t->phase = FC_TRIM_RAMPING;
                t->elapsed_s = 0.0f;
            }
            break;
        case FC_TRIM_RAMPING:
            t->elapsed_s += dt_s;
            if (!cfg->ramp_enable || t->elapsed_s >= cfg->ramp_s) {
                t->phase = FC_TRIM_DONE;
            }
            break;
        default:
            break;
        }
    }
    float frac = 0.0f;
    if (t->phase == FC_TRIM_DONE) {
        frac = 1.0f;
    } else if (t->phase == FC_TRIM_RAMPING) {
        frac = cfg->ramp_enable ? fc_constrainf(t->elapsed_s / cfg->ramp_s, 0.0f, 1.0f) : 1.0f;
    }
    for (int i = 0; i < 2; i++) {
        t->applied_us[i] = frac * t->learned_us[i];
        out_us[i] = t->applied_us[i];
    }
}
