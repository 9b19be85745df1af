/*
 * fc_rate_pid.c - rate PI + D on measurement (see fc_rate_pid.h).
 */
#include "fc_rate_pid.h"

#include "fc_math.h"

/* Without anti-windup the integrator is still bounded by the full authority,
 * so a float can never run away. */
#define FC_RATE_PID_I_HARD_LIMIT 1.0f

static int d_filter_kind(const fc_rate_pid_config_t *cfg)
{
    return cfg->d_pt2x2 ? FC_FILTER_PT2X2 : FC_FILTER_PT1;
}

/* Filter coefficients for the period dt_s (filter kinds kept). */
static void tune_filters(fc_rate_pid_t *pid, float dt_s)
{
    pid->dt_s = dt_s;
    fc_pt1_update_cutoff(&pid->target_lpf, pid->cfg.fltt_hz, dt_s);
    fc_pt1_update_cutoff(&pid->error_lpf, pid->cfg.flte_hz, dt_s);
    (void)fc_filter_update_cutoff(&pid->d_filter, pid->cfg.fltd_hz, 0.0f, dt_s);
}

void fc_rate_pid_configure(fc_rate_pid_t *pid, const fc_rate_pid_config_t *cfg, float dt_s)
{
    const bool kind_changed = (pid->d_filter.kind != d_filter_kind(cfg));
    pid->cfg = *cfg;
    if (kind_changed) {
        (void)fc_filter_init(&pid->d_filter, d_filter_kind(cfg), cfg->fltd_hz, 0.0f, dt_s);
        fc_filter_reset(&pid->d_filter, pid->meas_prev);
    }
    tune_filters(pid, dt_s);
}

void fc_rate_pid_reset(fc_rate_pid_t *pid)
{
    fc_pt1_reset(&pid->target_lpf, 0.0f);
    fc_pt1_reset(&pid->error_lpf, 0.0f);
    fc_filter_reset(&pid->d_filter, 0.0f);
    pid->meas_prev = 0.0f;
    pid->integ = 0.0f;
    pid->primed = false;
    fc_pid_info_t zero = {0};
    pid->info = zero;
}

void fc_rate_pid_reset_integrator(fc_rate_pid_t *pid)
{
    pid->integ = 0.0f;
}

void fc_rate_pid_init(fc_rate_pid_t *pid, const fc_rate_pid_config_t *cfg, float dt_s)
{
    pid->d_filter.kind = -1; /* force the D filter to be built */
    pid->meas_prev = 0.0f;
    pid->target_lpf.k = 1.0f;
    pid->error_lpf.k = 1.0f;
    fc_rate_pid_configure(pid, cfg, dt_s);
    fc_rate_pid_reset(pid);
}

float fc_rate_pid_update(fc_rate_pid_t *pid, float target_rad_s, float meas_rad_s, float dt_s,
                         bool mixer_limit, bool integrate)
{
    if (!(dt_s > 0.0f) || !fc_finitef(dt_s)) {
        return pid->info.out_us;
    }
    if (fc_retune_needed(pid->dt_s, dt_s)) {
        tune_filters(pid, dt_s); /* the step's own period: the filters follow it */
    }
    if (!fc_finitef(target_rad_s) || !fc_finitef(meas_rad_s)) {
        return pid->info.out_us;
    }
    const fc_rate_pid_config_t *cfg = &pid->cfg;
    if (!pid->primed) {
        /* Start every filter at the present value: no derivative or error kick. */
        fc_pt1_reset(&pid->target_lpf, target_rad_s);
        fc_pt1_reset(&pid->error_lpf, target_rad_s - meas_rad_s);
        fc_filter_reset(&pid->d_filter, meas_rad_s);
        pid->meas_prev = meas_rad_s;
        pid->primed = true;
    }
    const float target = fc_pt1_apply(&pid->target_lpf, target_rad_s);
    const float error = fc_pt1_apply(&pid->error_lpf, target - meas_rad_s);

    /* D on measurement. */
    const float meas_f = fc_filter_apply(&pid->d_filter, meas_rad_s);
    const float d_rate = (meas_f - pid->meas_prev) / dt_s;
    pid->meas_prev = meas_f;
    float d_us = -cfg->kd * d_rate * cfg->out_us_per_unit;
    uint8_t d_clamped = 0;
    if (cfg->d_clamp_enable) {
        const float c = cfg->d_clamp_us;
        if (d_us > c || d_us < -c) {
            d_us = fc_constrainf(d_us, -c, c);
            d_clamped = 1;
        }
    }

    /* I: conditional integration, clamp, no growth while the mixer saturates. */
    const float i_limit = cfg->antiwindup ? cfg->imax : FC_RATE_PID_I_HARD_LIMIT;
    uint8_t limited = 0;
    if (integrate) {
        const float candidate = pid->integ + cfg->ki * error * dt_s;
        if (cfg->antiwindup && mixer_limit && fabsf(candidate) > fabsf(pid->integ)) {
            limited = 1; /* may shrink, may not grow */
        } else {
            pid->integ = candidate;
        }
    }
    if (pid->integ > i_limit || pid->integ < -i_limit) {
        pid->integ = fc_constrainf(pid->integ, -i_limit, i_limit);
        limited = 1;
    }
    if (mixer_limit && cfg->antiwindup) {
        limited = 1;
    }

    fc_pid_info_t *info = &pid->info;
    info->target_rad_s = target;
    info->actual_rad_s = meas_rad_s;
    info->error_rad_s = error;
    info->p_us = cfg->kp * error * cfg->out_us_per_unit;
    info->i_us = pid->integ * cfg->out_us_per_unit;
    info->d_us = d_us;
    info->ff_us = cfg->kff * target * cfg->out_us_per_unit;
    info->out_us = info->p_us + info->i_us + info->d_us + info->ff_us;
    info->limited = limited;
    info->d_clamped = d_clamped;
    return info->out_us;
}
