/*
 * fc_sched.h - estimator gains scheduled by flight phase and by evidence.
 *
 * Two estimators trade noise against robustness through one gain each, and
 * no single value wins both (issue 14): at hover a slow vertical filter
 * (SB_ALT_TC_HOLD 8 s) and low GNSS-aided Mahony gains (SB_AHRS_GPS_KP 0.3,
 * KI 0.05) halve the PWM peak-to-peak and lower the attitude error, but the
 * slow filter lags a touchdown (the landing is detected late) and the low
 * integral gain learns a gyro-bias step four times slower (7.8 deg of tilt
 * error instead of < 3). So each estimator runs its quiet gain only while the
 * evidence says nothing is happening, and its fast one otherwise:
 *
 * Vertical (fc_alt_sched): the quiet time constant only while the vehicle
 * holds an altitude in steady flight (the host's phase evidence: airborne,
 * altitude mode, target above the landing height and near the estimate, no
 * climb demand; the last two graded, so the loop's own correction of a
 * drifted estimate does not switch the time constant in one step) AND the low-passed baro innovation (baro - estimate) stays
 * below SB_ALT_INNOV; else SB_ALT_TC. The innovation half catches what no
 * demand announces (a push by the air, an accelerometer shift).
 *
 * Aided tilt (fc_aid_sched): the GNSS-aided tilt error of each fix is
 * low-passed (FC_AID_LP_TC_S); noise averages out of that mean, a real tilt
 * or bias error does not. Its size is compared with the noise the mean would
 * show, measured in flight from the fix-to-fix changes of the error; above
 * SB_AHRS_GPS_INN times that noise (never below FC_AID_FLOOR_RAD) the
 * bandwidth of the aided PI rises smoothly, up to SB_AHRS_GPS_BST times:
 * KP x s and KI x s^2, which keeps its damping (KP = 2 zeta w, KI = w^2).
 *
 * Both leave their quiet gain slowly and return to it slowly: a weight
 * w in 0..1 (1 = fast gains) jumps up to the demand at once (a fault must be
 * met now) and relaxes down to it with a time constant (a quiet stretch must
 * last before the filter trusts it). Gains blend geometrically in w, so a
 * time constant or a bandwidth changes by the same ratio per step of w.
 */
#ifndef FC_SCHED_H
#define FC_SCHED_H

#include <stdbool.h>

/* The attack/release weight: up to demand (0..1) at once, down with release_s. */
float fc_sched_weight(float w, float demand, float release_s, float dt_s);

/* ---- vertical complementary filter time constant ---------------------- */

typedef struct fc_alt_sched_config {
    float tc_s;      /* SB_ALT_TC: the fast time constant [s] */
    float tc_hold_s; /* SB_ALT_TC_HOLD: the quiet one, holding in steady flight [s] */
    float innov_m;   /* SB_ALT_INNOV: low-passed innovation that asks for the fast one [m] */
} fc_alt_sched_config_t;

typedef struct fc_alt_sched {
    float innov_lp_m; /* low-passed baro innovation, baro - estimate [m] */
    float w_fast;     /* 1 = tc_s, 0 = tc_hold_s */
    float tc_s;       /* the time constant in use [s] */
} fc_alt_sched_t;

/* Fast (w 1): a filter that starts on the ground starts fast. */
void fc_alt_sched_reset(fc_alt_sched_t *s, const fc_alt_sched_config_t *cfg);
/* One baro sample: seek is the phase evidence (the demand for the fast
 * time constant: <= 0 holding, >= 1 not holding, between while the hold
 * loop seeks its target; NaN counts as 1), innov_m this sample's
 * innovation. Returns the time constant for this sample [s]. */
float fc_alt_sched_step(fc_alt_sched_t *s, const fc_alt_sched_config_t *cfg, float seek,
                        float innov_m, float dt_s);

/* ---- GNSS-aided tilt gains --------------------------------------------- */

typedef struct fc_aid_sched_config {
    float boost;       /* SB_AHRS_GPS_BST: largest bandwidth factor (1 = fixed gains) */
    float innov_sigma; /* SB_AHRS_GPS_INN: threshold in noise sigmas of the mean */
} fc_aid_sched_config_t;

typedef struct fc_aid_sched {
    float innov_lp_rad[2]; /* low-passed aided tilt error, NED north/east [rad] */
    float prev_rad[2];     /* previous fix's error, for the noise estimate [rad] */
    bool have_prev;
    float noise_sum;       /* EMA of the mean's noise variance (bias-corrected by wsum) */
    float noise_wsum;      /* EMA of 1 with the same weights */
    float sigma_rad;       /* noise sigma of the mean, sqrt(sum / wsum), per fix [rad] */
    float lp_dt_s;         /* the step period lp_alpha was computed for [s] */
    float lp_alpha;        /* low-pass weight per step: one expf per period change */
    float w;               /* 0 = configured gains, 1 = boosted by `boost` */
    float scale;           /* bandwidth factor in use, 1..boost */
} fc_aid_sched_t;

void fc_aid_sched_reset(fc_aid_sched_t *s);
/* A new fix's aided tilt error (NED, north/east used), fix_dt_s after the previous one. */
void fc_aid_sched_fix(fc_aid_sched_t *s, const float err_ned_rad[3], float fix_dt_s);
/* One estimator step with the held error; returns the bandwidth factor s
 * (KP x s, KI x s^2). */
float fc_aid_sched_step(fc_aid_sched_t *s, const fc_aid_sched_config_t *cfg,
                        const float err_ned_rad[3], float dt_s);

#endif /* FC_SCHED_H */
