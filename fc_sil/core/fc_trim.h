/*
 * fc_trim.h - hover-trim learning with ramp-in (paper 3.7).
 *
 * From lift-off, the small-angle errors (ex, ey) are averaged over a window
 * (3 s); the mean times a gain (80 us/rad), saturated (+-50 us), becomes a
 * roll/pitch offset added to the rate-loop outputs before the mixer. It is
 * brought in with a linear ramp (0.8 s) so the hand-over from the integrators
 * makes no step. Sign: a positive mean roll error (the vehicle sits rolled
 * left of its target) needs positive roll output, so trim = +gain * mean.
 */
#ifndef FC_TRIM_H
#define FC_TRIM_H

#include <stdbool.h>
#include <stdint.h>

typedef struct fc_trim_config {
    bool enable;           /* learn at all */
    bool ramp_enable;      /* false: the learned trim applies as a step (ablation) */
    float window_s;        /* averaging window after lift-off [s] */
    float gain_us_per_rad; /* trim per rad of mean error [us/rad] */
    float max_us;          /* saturation, +- [us] */
    float ramp_s;          /* ramp-in time [s] */
} fc_trim_config_t;

typedef enum fc_trim_phase {
    FC_TRIM_WAITING = 0,  /* not airborne yet */
    FC_TRIM_LEARNING = 1, /* averaging */
    FC_TRIM_RAMPING = 2,  /* learned, coming in */
    FC_TRIM_DONE = 3      /* fully applied */
} fc_trim_phase_t;

typedef struct fc_trim {
    uint8_t phase;           /* fc_trim_phase_t */
    float elapsed_s;         /* time in the current phase [s] */
    float err_sum_rad_s[2];  /* integral of (ex, ey) over the window [rad s] */
    float learned_us[2];     /* saturated trim, roll and pitch [us] */
    float applied_us[2];     /* what goes to the mixer now [us] */
} fc_trim_t;

void fc_trim_reset(fc_trim_t *t);
/* One control step; returns applied_us through out_us[2] (roll, pitch). */
void fc_trim_update(fc_trim_t *t, const fc_trim_config_t *cfg, bool airborne, float ex_rad,
                    float ey_rad, float dt_s, float out_us[2]);

#endif /* FC_TRIM_H */
