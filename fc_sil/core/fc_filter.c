/*
 * fc_filter.c - PT1, PT2, PT2x2 and biquad filters (see fc_filter.h for the
 * cutoff correction and the scipy equivalents the tests check against).
 */
#include "fc_filter.h"

#include <math.h>
#include <stddef.h>

#include "fc_math.h"

/* Per-stage gain k of a PT1 stage y += k (x - y) such that n such stages in
 * series are exactly -3 dB at cutoff_hz at this sample period. The power gain
 * of one discrete stage at w = 2 pi f dt is k^2 / (1 - 2 (1-k) cos w + (1-k)^2);
 * setting it to G = 2^(-1/n) gives a quadratic in k whose root in (0, 1) is
 *     k = (sqrt(D (D + 2A)) - D) / A,  A = 1 - G,  D = 2 G sin^2(w/2)
 * (written with sin^2(w/2) instead of 1 - cos w so float32 keeps its digits at
 * a 32 kHz loop). For f << 1/dt, k -> w sqrt(G/A) = w / sqrt(2^(1/n) - 1):
 * Betaflight's analog cutoff correction (1.5538 for PT2, 2.2990 for PT2x2),
 * which the exact form keeps accurate near Nyquist as well. */
static float ptn_stage_gain(float cutoff_hz, float dt_s, int n_stages)
{
    if (!(cutoff_hz > 0.0f) || !(dt_s > 0.0f) || !fc_finitef(cutoff_hz) || !fc_finitef(dt_s)) {
        return 1.0f;
    }
    const float w = FC_TWO_PI_F * fminf(cutoff_hz * dt_s, 0.5f);
    const float g = (n_stages == 1) ? 0.5f : (n_stages == 2) ? 0.70710678f : 0.84089642f;
    const float a = 1.0f - g;
    const float s = sinf(0.5f * w);
    const float d = 2.0f * g * s * s;
    return fc_constrainf((sqrtf(d * (d + 2.0f * a)) - d) / a, 0.0f, 1.0f);
}

float fc_pt1_gain(float cutoff_hz, float dt_s)
{
    return ptn_stage_gain(cutoff_hz, dt_s, 1);
}

/* One stage. k x + (1 - k) y rather than y + k (x - y): with k = 1
 * (pass-through) the output is exactly x. */
static inline float stage(float y, float x, float k)
{
    return k * x + (1.0f - k) * y;
}

/* ---- PT1 ---------------------------------------------------------------- */

void fc_pt1_init(fc_pt1_t *f, float cutoff_hz, float dt_s)
{
    f->state = 0.0f;
    f->k = fc_pt1_gain(cutoff_hz, dt_s);
}

void fc_pt1_update_cutoff(fc_pt1_t *f, float cutoff_hz, float dt_s)
{
    f->k = fc_pt1_gain(cutoff_hz, dt_s);
}

void fc_pt1_reset(fc_pt1_t *f, float value)
{
    f->state = value;
}

float fc_pt1_apply(fc_pt1_t *f, float x)
{
    f->state = stage(f->state, x, f->k);
    return f->state;
}

/* ---- PT2 ---------------------------------------------------------------- */

void fc_pt2_init(fc_pt2_t *f, float cutoff_hz, float dt_s)
{
    f->state1 = 0.0f;
    f->state = 0.0f;
    fc_pt2_update_cutoff(f, cutoff_hz, dt_s);
}

void fc_pt2_update_cutoff(fc_pt2_t *f, float cutoff_hz, float dt_s)
{
    f->k = ptn_stage_gain(cutoff_hz, dt_s, 2);
}

void fc_pt2_reset(fc_pt2_t *f, float value)
{
    f->state1 = value;
    f->state = value;
}

float fc_pt2_apply(fc_pt2_t *f, float x)
{
    f->state1 = stage(f->state1, x, f->k);
    f->state = stage(f->state, f->state1, f->k);
    return f->state;
}

/* ---- PT2x2 -------------------------------------------------------------- */

void fc_pt2x2_init(fc_pt2x2_t *f, float cutoff_hz, float dt_s)
{
    fc_pt2x2_reset(f, 0.0f);
    fc_pt2x2_update_cutoff(f, cutoff_hz, dt_s);
}

void fc_pt2x2_update_cutoff(fc_pt2x2_t *f, float cutoff_hz, float dt_s)
{
    f->k = ptn_stage_gain(cutoff_hz, dt_s, 4);
}

void fc_pt2x2_reset(fc_pt2x2_t *f, float value)
{
    for (int i = 0; i < 4; i++) {
        f->state[i] = value;
    }
}

float fc_pt2x2_apply(fc_pt2x2_t *f, float x)
{
    float in = x;
    for (int i = 0; i < 4; i++) {
        f->state[i] = stage(f->state[i], in, f->k);
        in = f->state[i];
    }
    return in;
}

/* ---- biquads ------------------------------------------------------------ */

static void biquad_passthrough(fc_biquad_t *f)
{
    f->b0 = 1.0f;
    f->b1 = 0.0f;
    f->b2 = 0.0f;
    f->a1 = 0.0f;
    f->a2 = 0.0f;
    f->d1 = 2.0f;
    f->d2 = 1.0f;
    f->bypass = true;
}

fc_status_t fc_biquad_update_lpf(fc_biquad_t *f, float cutoff_hz, float dt_s)
{
    if (!fc_finitef(cutoff_hz) || !(dt_s > 0.0f) || !fc_finitef(dt_s)) {
        biquad_passthrough(f);
        return FC_ERR_ARG;
    }
    if (cutoff_hz <= 0.0f) {
        biquad_passthrough(f);
        return FC_OK;
    }
    if (cutoff_hz >= 0.5f / dt_s) {
        biquad_passthrough(f); /* nothing to remove below Nyquist */
        return FC_ERR_ARG;
    }
    /* Bilinear transform of the 2nd-order Butterworth with the cutoff pre-warped. */
    const float q = 0.70710678f;
    const float kk = tanf(FC_PI_F * cutoff_hz * dt_s);
    const float kk2 = kk * kk;
    const float norm = 1.0f / (1.0f + kk / q + kk2);
    f->a1 = 2.0f * (kk2 - 1.0f) * norm;
    f->a2 = (1.0f - kk / q + kk2) * norm;
    f->bypass = false;
    f->d1 = 2.0f * (kk / q + 2.0f * kk2) * norm; /* 2 + a1 */
    f->d2 = 2.0f * (kk / q) * norm;              /* 1 - a2 */
    /* b = K^2 norm [1 2 1] = (1 + a1 + a2) / 4 [1 2 1]; taken from d1 - d2 so the
     * DC gain is 1 to the last bit (reset then constant input stays constant). */
    f->b0 = 0.25f * (f->d1 - f->d2);
    f->b1 = 2.0f * f->b0;
    f->b2 = f->b0;
    return FC_OK;
}

fc_status_t fc_biquad_init_lpf(fc_biquad_t *f, float cutoff_hz, float dt_s)
{
    fc_status_t st = fc_biquad_update_lpf(f, cutoff_hz, dt_s);
    fc_biquad_reset(f, 0.0f);
    return st;
}

fc_status_t fc_biquad_update_notch(fc_biquad_t *f, float center_hz, float bandwidth_hz,
                                   float dt_s)
{
    if (!fc_finitef(center_hz) || !fc_finitef(bandwidth_hz) || !(dt_s > 0.0f)
        || !fc_finitef(dt_s)) {
        biquad_passthrough(f);
        return FC_ERR_ARG;
    }
    if (center_hz <= 0.0f) {
        biquad_passthrough(f);
        return FC_OK;
    }
    const float nyquist_hz = 0.5f / dt_s;
    if (!(bandwidth_hz > 0.0f) || center_hz + 0.5f * bandwidth_hz >= nyquist_hz
        || center_hz - 0.5f * bandwidth_hz <= 0.0f) {
        biquad_passthrough(f);
        return FC_ERR_ARG;
    }
    /* Bilinear notch whose -3 dB points are bandwidth_hz apart (scipy iirnotch). */
    const float w0 = FC_TWO_PI_F * center_hz * dt_s;
    const float bw = FC_TWO_PI_F * bandwidth_hz * dt_s;
    const float gain = 1.0f / (1.0f + tanf(0.5f * bw));
    const float c = cosf(w0);
    f->a1 = -2.0f * gain * c;
    f->a2 = 2.0f * gain - 1.0f;
    f->bypass = false;
    f->d1 = 2.0f + f->a1; /* the notch's poles are not near z = 1: no cancellation */
    f->d2 = 1.0f - f->a2;
    /* b0 = b2 = gain, written as (1 + a2) / 2 so that b0 + b1 + b2 = 1 + a1 + a2
     * exactly: unity DC gain to the last bit. */
    f->b0 = 0.5f * (1.0f + f->a2);
    f->b1 = f->a1;
    f->b2 = f->b0;
    return FC_OK;
}

fc_status_t fc_biquad_init_notch(fc_biquad_t *f, float center_hz, float bandwidth_hz, float dt_s)
{
    fc_status_t st = fc_biquad_update_notch(f, center_hz, bandwidth_hz, dt_s);
    fc_biquad_reset(f, 0.0f);
    return st;
}

void fc_biquad_reset(fc_biquad_t *f, float value)
{
    /* Fill the history with the steady state for a constant input `value`. */
    const float den = f->d1 - f->d2; /* 1 + a1 + a2 */
    const float dc_gain = (fabsf(den) > 1e-12f) ? (f->b0 + f->b1 + f->b2) / den : 1.0f;
    f->x1 = value;
    f->x2 = value;
    f->y1 = value * dc_gain;
    f->y2 = value * dc_gain;
}

float fc_biquad_apply(fc_biquad_t *f, float x)
{
    if (f->bypass) {
        f->x2 = f->x1;
        f->x1 = x;
        f->y2 = f->y1;
        f->y1 = x;
        return x;
    }
    /* -a1 y1 - a2 y2, regrouped so the small d1, d2 carry the pole positions. */
    const float y = (f->b0 * x + f->b1 * f->x1 + f->b2 * f->x2)
                    + (f->y1 + (f->y1 - f->y2)) - f->d1 * f->y1 + f->d2 * f->y2;
    f->x2 = f->x1;
    f->x1 = x;
    f->y2 = f->y1;
    f->y1 = y;
    return y;
}

/* ---- choose-once wrapper ----------------------------------------------- */

static float apply_null(fc_filter_t *f, float x)
{
    (void)f;
    return x;
}

static float apply_pt1(fc_filter_t *f, float x)
{
    return fc_pt1_apply(&f->u.pt1, x);
}

static float apply_pt2(fc_filter_t *f, float x)
{
    return fc_pt2_apply(&f->u.pt2, x);
}

static float apply_pt2x2(fc_filter_t *f, float x)
{
    return fc_pt2x2_apply(&f->u.pt2x2, x);
}

static float apply_biquad(fc_filter_t *f, float x)
{
    return fc_biquad_apply(&f->u.biquad, x);
}

fc_status_t fc_filter_update_cutoff(fc_filter_t *f, float cutoff_hz, float bandwidth_hz,
                                    float dt_s)
{
    switch (f->kind) {
    case FC_FILTER_PT1:
        fc_pt1_update_cutoff(&f->u.pt1, cutoff_hz, dt_s);
        return FC_OK;
    case FC_FILTER_PT2:
        fc_pt2_update_cutoff(&f->u.pt2, cutoff_hz, dt_s);
        return FC_OK;
    case FC_FILTER_PT2X2:
        fc_pt2x2_update_cutoff(&f->u.pt2x2, cutoff_hz, dt_s);
        return FC_OK;
    case FC_FILTER_BIQUAD_LPF:
        return fc_biquad_update_lpf(&f->u.biquad, cutoff_hz, dt_s);
    case FC_FILTER_NOTCH:
        return fc_biquad_update_notch(&f->u.biquad, cutoff_hz, bandwidth_hz, dt_s);
    default:
        return FC_OK;
    }
}

fc_status_t fc_filter_init(fc_filter_t *f, int kind, float cutoff_hz, float bandwidth_hz,
                           float dt_s)
{
    fc_status_t st = FC_OK;
    f->kind = kind;
    switch (kind) {
    case FC_FILTER_NONE:
        f->apply = apply_null;
        break;
    case FC_FILTER_PT1:
        f->apply = apply_pt1;
        break;
    case FC_FILTER_PT2:
        f->apply = apply_pt2;
        break;
    case FC_FILTER_PT2X2:
        f->apply = apply_pt2x2;
        break;
    case FC_FILTER_BIQUAD_LPF:
    case FC_FILTER_NOTCH:
        f->apply = apply_biquad;
        break;
    default:
        f->kind = FC_FILTER_NONE;
        f->apply = apply_null;
        st = FC_ERR_ARG;
        break;
    }
    if (st == FC_OK) {
        st = fc_filter_update_cutoff(f, cutoff_hz, bandwidth_hz, dt_s);
    }
    fc_filter_reset(f, 0.0f);
    return st;
}

void fc_filter_reset(fc_filter_t *f, float value)
{
    switch (f->kind) {
    case FC_FILTER_PT1:
        fc_pt1_reset(&f->u.pt1, value);
        break;
    case FC_FILTER_PT2:
        fc_pt2_reset(&f->u.pt2, value);
        break;
    case FC_FILTER_PT2X2:
        fc_pt2x2_reset(&f->u.pt2x2, value);
        break;
    case FC_FILTER_BIQUAD_LPF:
    case FC_FILTER_NOTCH:
        fc_biquad_reset(&f->u.biquad, value);
        break;
    default:
        break;
    }
}
