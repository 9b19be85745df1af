/*
 * fc_sched.c - estimator gains scheduled by flight phase and evidence (see
 * fc_sched.h for why and how).
 */
#include "fc_sched.h"

#include "fc_math.h"

/* Vertical: the baro innovation's low-pass. Baro noise (1.2 Pa ~ 0.1 m at
 * 100 Hz) leaves about 0.007 m in a 1 s mean, far below SB_ALT_INNOV, while
 * a lag or drift of the filter shows within a second. */
#define FC_ALT_LP_TC_S 1.0f
/* Back from the fast to the quiet time constant over a few seconds: the
 * filter has settled before it is slowed, and a short calm inside a
 * manoeuvre does not slow it. */
#define FC_ALT_RELEASE_S 2.0f

/* Aided tilt: the error's low-pass. Short, because a gyro-bias step grows
 * the tilt error at the bias rate (0.057 rad/s = 3.2 deg/s in the bias test)
 * and the evidence already arrives GPS_DELAY_MS plus a fix interval late;
 * long enough that a fix's velocity noise, which enters two successive
 * errors with opposite signs, largely cancels in the mean. */
#define FC_AID_LP_TC_S 0.2f
/* The noise estimate's memory: long against the 0.1 s fixes (a steady
 * figure), short against a flight (it follows vibration and GNSS changes). */
#define FC_AID_NOISE_TC_S 10.0f
/* The threshold never goes below this mean error [rad] (0.35 deg): with
 * noise-free velocity (a simulation without noise) the manoeuvres' own
 * residual errors (latency, heading) are of this size and are no fault. */
#define FC_AID_FLOOR_RAD 0.006f
/* Back to the quiet gains once the bias is learned: the boosted PI (KP 0.9,
 * KI 0.45 at the default factor 3) settles in about 3 s. */
#define FC_AID_RELEASE_S 3.0f

float fc_sched_weight(float w, float demand, float release_s, float dt_s)
{
    /* Nonsense evidence asks for the fast gains. */
    const float d = fc_finitef(demand) ? fc_constrainf(demand, 0.0f, 1.0f) : 1.0f;
    if (!(d < w)) {
        return d;
    }
    return w + fc_ema_alpha(dt_s, release_s) * (d - w);
}

/* a at w = 0, b at w = 1, the same ratio per step of w between. */
static float geometric_blend(float a, float b, float w)
{
    if (w == 0.0f) {
        return a;           /* exactly a * powf(b / a, 0): no powf at the quiet gains */
    }
    if (!(a > 0.0f) || !(b > 0.0f)) {
        return (w < 0.5f) ? a : b;
    }
    return a * powf(b / a, w);
}

/* ---- vertical ------------------------------------------------------------- */

void fc_alt_sched_reset(fc_alt_sched_t *s, const fc_alt_sched_config_t *cfg)
{
    s->innov_lp_m = 0.0f;
    s->w_fast = 1.0f;
    s->tc_s = cfg->tc_s;
}

float fc_alt_sched_step(fc_alt_sched_t *s, const fc_alt_sched_config_t *cfg, float seek,
                        float innov_m, float dt_s)
{
    if (fc_finitef(innov_m) && dt_s > 0.0f) {
        s->innov_lp_m += fc_ema_alpha(dt_s, FC_ALT_LP_TC_S) * (innov_m - s->innov_lp_m);
    }
    /* Smooth: from no demand at SB_ALT_INNOV to full at twice that. */
    const float thr = fmaxf(cfg->innov_m, 1e-3f);
    const float innov = fc_constrainf(fabsf(s->innov_lp_m) / thr - 1.0f, 0.0f, 1.0f);
    /* fc_sched_weight reads a NaN seek as full demand. */
    const float demand = (seek > innov) ? seek : (fc_finitef(seek) ? innov : seek);
    s->w_fast = fc_sched_weight(s->w_fast, demand, FC_ALT_RELEASE_S, dt_s);
    s->tc_s = geometric_blend(cfg->tc_hold_s, cfg->tc_s, s->w_fast);
    return s->tc_s;
}

/* ---- GNSS-aided tilt --------------------------------------------------------- */

void fc_aid_sched_reset(fc_aid_sched_t *s)
{
    for (int i = 0; i < 2; i++) {
        s->innov_lp_rad[i] = 0.0f;
        s->prev_rad[i] = 0.0f;
    }
    s->have_prev = false;
    s->noise_sum = 0.0f;
    s->noise_wsum = 0.0f;
    s->sigma_rad = 0.0f;
    s->lp_dt_s = -1.0f;
    s->lp_alpha = 0.0f;
    s->w = 0.0f;
    s->scale = 1.0f;
}

void fc_aid_sched_fix(fc_aid_sched_t *s, const float err_ned_rad[3], float fix_dt_s)
{
    if (!fc_finitef(err_ned_rad[0]) || !fc_finitef(err_ned_rad[1])) {
        return;
    }
    if (s->have_prev && fix_dt_s > 0.0f) {
        /* Per axis, white noise of variance v per fix: the change between two
         * fixes has variance 2 v (so v = |d|^2 / 4 over two axes), and an EMA
         * of weight a per fix keeps v a / (2 - a) of it in its mean. GNSS
         * velocity noise cancels better than white in the mean (see above),
         * so this overstates it; SB_AHRS_GPS_INN is counted in these units. */
        const float d0 = err_ned_rad[0] - s->prev_rad[0];
        const float d1 = err_ned_rad[1] - s->prev_rad[1];
        const float a = fc_ema_alpha(fix_dt_s, FC_AID_LP_TC_S);
        const float v_mean = 0.25f * (d0 * d0 + d1 * d1) * a / (2.0f - a);
        const float b = fc_ema_alpha(fix_dt_s, FC_AID_NOISE_TC_S);
        s->noise_sum += b * (v_mean - s->noise_sum);
        s->noise_wsum += b * (1.0f - s->noise_wsum);
        /* noise_sum / noise_wsum: the EMA without its start-up bias towards 0. */
        s->sigma_rad = (s->noise_wsum > 0.0f) ? sqrtf(s->noise_sum / s->noise_wsum) : 0.0f;
    }
    s->prev_rad[0] = err_ned_rad[0];
    s->prev_rad[1] = err_ned_rad[1];
    s->have_prev = true;
}

float fc_aid_sched_step(fc_aid_sched_t *s, const fc_aid_sched_config_t *cfg,
                        const float err_ned_rad[3], float dt_s)
{
    /* Per IMU sample: the period is nearly always the same, so its expf is kept. */
    if (dt_s != s->lp_dt_s) {
        s->lp_dt_s = dt_s;
        s->lp_alpha = fc_ema_alpha(dt_s, FC_AID_LP_TC_S);
    }
    const float a = s->lp_alpha;
    for (int i = 0; i < 2; i++) {
        s->innov_lp_rad[i] += a * (err_ned_rad[i] - s->innov_lp_rad[i]);
    }
    const float thr = fmaxf(FC_AID_FLOOR_RAD, cfg->innov_sigma * s->sigma_rad);
    const float mag = sqrtf(fc_sq(s->innov_lp_rad[0]) + fc_sq(s->innov_lp_rad[1]));
    /* Smooth: from no boost at the threshold to the full one at twice it. */
    const float demand = mag / thr - 1.0f;
    s->w = fc_sched_weight(s->w, demand, FC_AID_RELEASE_S, dt_s);
    s->scale = geometric_blend(1.0f, fmaxf(cfg->boost, 1.0f), s->w);
    return s->scale;
}
