/*
 * fc_vibe.c - vibration levels and clipping (see fc_vibe.h for the algorithm and its source).
 */
#include "fc_vibe.h"

#include <math.h>

#define FC_VIBE_TWO_PI 6.28318530717958647692f

void fc_vibe_init(fc_vibe_t *v, float clip_m_s2)
{
    fc_vibe_t z = {0};
    *v = z;
    v->clip_m_s2 = (isfinite(clip_m_s2) && clip_m_s2 > 0.0f) ? clip_m_s2 : FC_VIBE_CLIP_16G_M_S2;
}

/* ArduPilot's calc_lowpass_alpha_dt: the first-order filter's gain for one step. */
static float lowpass_alpha(float dt_s, float cutoff_hz)
{
    const float rc = 1.0f / (FC_VIBE_TWO_PI * cutoff_hz);
    return dt_s / (dt_s + rc);
}

void fc_vibe_apply(fc_vibe_t *v, const float a[3], float dt_s)
{
    if (!isfinite(a[0]) || !isfinite(a[1]) || !isfinite(a[2])) {
        return;
    }
    const float lim = v->clip_m_s2;
    if (fabsf(a[0]) > lim || fabsf(a[1]) > lim || fabsf(a[2]) > lim) {
        v->clip_count++;
    }
    v->samples++;
    if (!v->initialised) {
        for (int i = 0; i < 3; i++) {
            v->floor_m_s2[i] = a[i];
            v->vibe_m2_s4[i] = 0.0f; /* (a - floor)^2 of the first sample */
        }
        v->initialised = true;
        return;
    }
    if (!(dt_s > 0.0f)) {
        return;
    }
    const float k_floor = lowpass_alpha(dt_s, FC_VIBE_FLOOR_HZ);
    const float k_vibe = lowpass_alpha(dt_s, FC_VIBE_FILT_HZ);
    for (int i = 0; i < 3; i++) {
        v->floor_m_s2[i] += (a[i] - v->floor_m_s2[i]) * k_floor;
        const float d = a[i] - v->floor_m_s2[i];
        v->vibe_m2_s4[i] += (d * d - v->vibe_m2_s4[i]) * k_vibe;
    }
}

void fc_vibe_levels(const fc_vibe_t *v, float out_m_s2[3])
{
    for (int i = 0; i < 3; i++) {
        out_m_s2[i] = v->vibe_m2_s4[i] > 0.0f ? sqrtf(v->vibe_m2_s4[i]) : 0.0f; /* safe_sqrt */
    }
}
