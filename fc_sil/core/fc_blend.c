/*
 * fc_blend.c - continuous estimate/ground-truth blending (see fc_blend.h).
 */
#include "fc_blend.h"

#include "fc_math.h"

void fc_blend_reset(fc_blend_t *b, float w)
{
    b->w = fc_constrainf(w, 0.0f, 1.0f);
}

float fc_blend_update(fc_blend_t *b, float target_w, float tau_s, bool continuous, float dt_s)
{
    if (!fc_finitef(target_w) || !(dt_s >= 0.0f) || !fc_finitef(dt_s)) {
        return b->w;
    }
    const float target = fc_constrainf(target_w, 0.0f, 1.0f);
    if (continuous) {
        b->w += fc_ema_alpha(dt_s, tau_s) * (target - b->w);
    } else {
        b->w = target;
    }
    return b->w;
}

void fc_blend_mix(float w, const float *a, const float *b, float *out, int n)
{
    for (int i = 0; i < n; i++) {
        out[i] = (1.0f - w) * a[i] + w * b[i];
    }
}
