/*
 * fc_filter.h - the low-pass and notch filters of the flight-controller core.
 *
 * Each filter is a state struct and four verbs: gain/coefficients, init,
 * update_cutoff (new cutoff, state kept, so a parameter change takes effect
 * without a glitch), reset (to a value: reset then constant input gives no
 * transient) and apply. A cutoff of 0 means pass-through.
 *
 * PTn filters are n identical PT1 stages. Their per-stage cutoff is raised so
 * that the whole cascade is -3 dB at the requested cutoff. For the analog
 * prototype:
 *     |H(f)|^2 = (1 + (f/f_stage)^2)^-n = 1/2 at f = f_c
 *     =>  f_stage = f_c / sqrt(2^(1/n) - 1)
 * which is 1.5538 for PT2 (n = 2) and 2.2990 for PT2x2 (two PT2 in series,
 * n = 4): Betaflight's correction. We solve the same condition for the
 * discrete stage exactly (fc_filter.c, ptn_stage_gain), which equals the
 * analog correction for f_c << 1/dt and stays exact near Nyquist (at 1 kHz the
 * analog correction leaves a PT2x2 at 20 Hz 0.8 dB low at its cutoff).
 * The PT2x2 is the paper's "2-stage PT2" D-term filter (3.6).
 *
 * The biquads are direct form I (robust to coefficient changes while running),
 * with the feedback written as y1 + (y1 - y2) - d1 y1 + d2 y2, d1 = 2 + a1 and
 * d2 = 1 - a2 computed analytically: at a low cutoff (20 Hz at 32 kHz) a1 and
 * a2 sit next to -2 and 1, and float32 would round away the poles' distance
 * from the unit circle (0.2 dB gain and 1 % DC errors at 100 kHz otherwise).
 * a Butterworth low-pass (bilinear transform with pre-warping, identical to
 * scipy.signal.butter(2, f_c, fs=1/dt)) and a notch given by centre and -3 dB
 * bandwidth (identical to scipy.signal.iirnotch(f0, f0/bw, fs=1/dt)).
 *
 * fc_filter_t is the "choose once" wrapper: the kind is fixed at init and the
 * apply function pointer selected then (a null filter for pass-through), so
 * the hot path has no switch.
 */
#ifndef FC_FILTER_H
#define FC_FILTER_H

#include <stdbool.h>

#include "fc_status.h"

typedef struct fc_pt1 {
    float state; /* output [input units] */
    float k;     /* gain per sample, 0..1 (1 = pass-through) */
} fc_pt1_t;

typedef struct fc_pt2 {
    float state1; /* first stage output */
    float state;  /* output */
    float k;      /* per-stage gain, corrected cutoff */
} fc_pt2_t;

typedef struct fc_pt2x2 {
    float state[4]; /* stage outputs; state[3] is the output */
    float k;        /* per-stage gain, corrected cutoff (four stages) */
} fc_pt2x2_t;

typedef struct fc_biquad {
    float b0, b1, b2, a1, a2; /* normalised coefficients (a0 = 1) */
    float d1, d2;             /* 2 + a1 and 1 - a2, computed without cancellation */
    float x1, x2, y1, y2;     /* past inputs and outputs */
    bool bypass;              /* pass-through (cutoff 0 or refused): output = input exactly */
} fc_biquad_t;

/* Per-stage PT1 gain for a cutoff [Hz] at a sample period [s]; cutoff <= 0 gives 1. */
float fc_pt1_gain(float cutoff_hz, float dt_s);

void fc_pt1_init(fc_pt1_t *f, float cutoff_hz, float dt_s);
void fc_pt1_update_cutoff(fc_pt1_t *f, float cutoff_hz, float dt_s);
void fc_pt1_reset(fc_pt1_t *f, float value);
float fc_pt1_apply(fc_pt1_t *f, float x);

void fc_pt2_init(fc_pt2_t *f, float cutoff_hz, float dt_s);
void fc_pt2_update_cutoff(fc_pt2_t *f, float cutoff_hz, float dt_s);
void fc_pt2_reset(fc_pt2_t *f, float value);
float fc_pt2_apply(fc_pt2_t *f, float x);

void fc_pt2x2_init(fc_pt2x2_t *f, float cutoff_hz, float dt_s);
void fc_pt2x2_update_cutoff(fc_pt2x2_t *f, float cutoff_hz, float dt_s);
void fc_pt2x2_reset(fc_pt2x2_t *f, float value);
float fc_pt2x2_apply(fc_pt2x2_t *f, float x);

/* Biquads return FC_ERR_ARG (and become pass-through) when the frequency is
 * at or above Nyquist or dt is not positive; cutoff/centre 0 is pass-through. */
fc_status_t fc_biquad_init_lpf(fc_biquad_t *f, float cutoff_hz, float dt_s);
fc_status_t fc_biquad_update_lpf(fc_biquad_t *f, float cutoff_hz, float dt_s);
fc_status_t fc_biquad_init_notch(fc_biquad_t *f, float center_hz, float bandwidth_hz, float dt_s);
fc_status_t fc_biquad_update_notch(fc_biquad_t *f, float center_hz, float bandwidth_hz,
                                   float dt_s);
void fc_biquad_reset(fc_biquad_t *f, float value);
float fc_biquad_apply(fc_biquad_t *f, float x);

/* ---- choose-once wrapper ---------------------------------------------- */

typedef enum fc_filter_kind {
    FC_FILTER_NONE = 0,
    FC_FILTER_PT1 = 1,
    FC_FILTER_PT2 = 2,
    FC_FILTER_PT2X2 = 3,
    FC_FILTER_BIQUAD_LPF = 4,
    FC_FILTER_NOTCH = 5
} fc_filter_kind_t;

struct fc_filter;
typedef float (*fc_filter_apply_fn)(struct fc_filter *f, float x);

typedef struct fc_filter {
    fc_filter_apply_fn apply; /* selected at init; never NULL after init */
    int kind;                 /* fc_filter_kind_t */
    union {
        fc_pt1_t pt1;
        fc_pt2_t pt2;
        fc_pt2x2_t pt2x2;
        fc_biquad_t biquad;
    } u;
} fc_filter_t;

/* bandwidth_hz is used by the notch only. Unknown kind: FC_ERR_ARG, pass-through. */
fc_status_t fc_filter_init(fc_filter_t *f, int kind, float cutoff_hz, float bandwidth_hz,
                           float dt_s);
/* New cutoff for the kind chosen at init; the state is kept. */
fc_status_t fc_filter_update_cutoff(fc_filter_t *f, float cutoff_hz, float bandwidth_hz,
                                    float dt_s);
void fc_filter_reset(fc_filter_t *f, float value);

static inline float fc_filter_apply(fc_filter_t *f, float x)
{
    return f->apply(f, x);
}

#endif /* FC_FILTER_H */
