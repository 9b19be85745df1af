/*
 * fc_blend.h - continuous estimate/ground-truth blending (paper 3.7, 2.4).
 *
 * The controllers use e = (1 - w) e_est + w e_gt. Switching the source moves
 * the weight w towards its new target (0 = estimate, 1 = ground truth) with a
 * first-order EMA of time constant tau (0.25 s), so a source change is never
 * a step. With `continuous` false (the ablation) w jumps: a discrete switch.
 */
#ifndef FC_BLEND_H
#define FC_BLEND_H

#include <stdbool.h>

typedef struct fc_blend {
    float w; /* weight of ground truth, 0..1 */
} fc_blend_t;

void fc_blend_reset(fc_blend_t *b, float w);
/* Move w towards `target_w`; returns the new w. */
float fc_blend_update(fc_blend_t *b, float target_w, float tau_s, bool continuous, float dt_s);
/* (1 - w) a + w b, element-wise over n values. */
void fc_blend_mix(float w, const float *a, const float *b, float *out, int n);

#endif /* FC_BLEND_H */
