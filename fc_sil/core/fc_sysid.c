/*
 * fc_sysid.c - the SYSTEMID chirp (see fc_sysid.h).
 */
#include "fc_sysid.h"

#include "fc_math.h"

void fc_sysid_reset(fc_sysid_t *s)
{
    const uint32_t runs = s->runs;
    s->active = false;
    s->axis = FC_SID_NONE;
    s->start_ns = 0;
    s->t_s = 0.0f;
    s->sample = 0.0f;
    s->freq_hz = 0.0f;
    s->runs = runs;
}

/* Two full cycles at the start frequency before the sweep (ArduCopter's). */
static float const_freq_s(const fc_sysid_config_t *cfg)
{
    return 2.0f / cfg->f_start_hz;
}

bool fc_sysid_config_valid(const fc_sysid_config_t *cfg)
{
    return cfg->axis != FC_SID_NONE && cfg->axis <= FC_SID_MIX_THROTTLE
           && cfg->f_start_hz > 0.0f && cfg->f_stop_hz > 0.0f && cfg->t_fade_in_s >= 0.0f
           && cfg->t_rec_s > 0.0f && cfg->t_fade_out_s >= 0.0f
           && cfg->t_rec_s > const_freq_s(cfg) && fc_finitef(cfg->magnitude);
}

float fc_sysid_waveform(const fc_sysid_config_t *cfg, float t_s, float *freq_hz)
{
    const float w_min = FC_TWO_PI_F * cfg->f_start_hz;
    const float w_max = FC_TWO_PI_F * cfg->f_stop_hz;
    const float rec = cfg->t_rec_s;
    const float fade_in = cfg->t_fade_in_s;
    const float fade_out = cfg->t_fade_out_s;
    const float tc = const_freq_s(cfg);
    float window;
    if (t_s <= 0.0f) {
        window = 0.0f;
    } else if (t_s <= fade_in) {
        window = 0.5f - 0.5f * cosf(FC_PI_F * t_s / fade_in);
    } else if (t_s <= rec - fade_out) {
        window = 1.0f;
    } else if (t_s <= rec) {
        /* falls from 1 to 0 over the last fade_out seconds */
        window = 0.5f - 0.5f * cosf(FC_PI_F * (t_s - (rec - fade_out)) / fade_out + FC_PI_F);
    } else {
        window = 0.0f;
    }
    float w = w_min;
    float out = 0.0f;
    if (t_s <= 0.0f) {
        out = 0.0f;
    } else if (t_s <= tc) {
        out = window * cfg->magnitude * sinf(w_min * t_s - w_min * tc);
    } else if (t_s <= rec) {
        /* Log sweep: w(t) = w_min exp(B (t - tc) / (rec - tc)), B = ln(w_max / w_min);
         * the phase is its integral from tc. */
        const float b = logf(w_max / w_min);
        const float span = rec - tc;
        const float g = expf(b * (t_s - tc) / span);
        w = w_min * g;
        out = window * cfg->magnitude * sinf((w_min * span / b) * (g - 1.0f));
    } else {
        w = w_max;
    }
    if (freq_hz != 0) {
        *freq_hz = w / FC_TWO_PI_F;
    }
    return out;
}

bool fc_sysid_start(fc_sysid_t *s, const fc_sysid_config_t *cfg, int64_t sim_ns)
{
    if (!fc_sysid_config_valid(cfg)) {
        return false;
    }
    fc_sysid_reset(s);
    s->active = true;
    s->axis = cfg->axis;
    s->start_ns = sim_ns;
    s->runs++;
    return true;
}

void fc_sysid_stop(fc_sysid_t *s)
{
    s->active = false;
    s->sample = 0.0f;
}

float fc_sysid_update(fc_sysid_t *s, const fc_sysid_config_t *cfg, int64_t sim_ns)
{
    if (!s->active) {
        s->sample = 0.0f;
        return 0.0f;
    }
    s->t_s = (float)(sim_ns - s->start_ns) * 1e-9f;
    if (s->t_s > FC_SYSID_DELAY_S + cfg->t_rec_s) {
        fc_sysid_stop(s); /* finished */
        return 0.0f;
    }
    s->sample = fc_sysid_waveform(cfg, s->t_s - FC_SYSID_DELAY_S, &s->freq_hz);
    return s->sample;
}
