/*
 * fc_notch.c - the harmonic notch (see fc_notch.h for the design and what
 * follows ArduCopter 4.6).
 */
#include "fc_notch.h"

#include <math.h>

#include "fc_math.h"

/* Harmonics at or above this fraction of the sample rate are off (ArduPilot's
 * HARMONIC_NYQUIST_CUTOFF: the notch's response folds near Nyquist). */
#define FC_NOTCH_NYQUIST_FRACTION 0.48f
/* A centre moves at most 5 % per update (ArduPilot's NOTCH_MAX_SLEW): a bad
 * rotor-speed reading perturbs the notch instead of throwing it away. */
#define FC_NOTCH_SLEW_LOWER 0.95f
/* Below FREQ x FM_RAT the attenuation fades out, to none at a quarter of it
 * (ArduPilot's NOTCHFILTER_ATTENUATION_CUTOFF), where the notch turns off. */
#define FC_NOTCH_OFF_FRACTION 0.25f
/* ArduCopter updates the centres at 200 Hz unless OPTS asks for every loop. */
#define FC_NOTCH_UPDATE_S 0.005f

enum { FC_NOTCH_FILTER_OFF = 0, FC_NOTCH_FILTER_START = 1, FC_NOTCH_FILTER_ON = 2 };

/* ---- design ------------------------------------------------------------- */

static uint8_t composite_count(uint16_t options)
{
    /* ArduPilot's precedence when several are set: double, then triple, then quintuple. */
    if (options & FC_NOTCH_OPT_DOUBLE) {
        return 2;
    }
    if (options & FC_NOTCH_OPT_TRIPLE) {
        return 3;
    }
    if (options & FC_NOTCH_OPT_QUINTUPLE) {
        return 5;
    }
    return 1;
}

/* Frequency multiplier of the j-th notch of a composite: the centre first
 * (odd counts), then symmetric pairs 1 -+ spread, 1 -+ 2 spread. */
static float spread_mul(const fc_notch_t *n, unsigned j)
{
    const unsigned pair = (n->composite % 2u == 1u) ? j + 1u : j + 2u;
    if (pair < 2u) {
        return 1.0f;
    }
    const float s = n->spread * (float)(pair / 2u);
    return (pair % 2u == 0u) ? 1.0f - s : 1.0f + s;
}

/* A, 1/Q, spread and the floor from the parameters, as ArduPilot's
 * HarmonicNotchFilter::init: Q is designed at FREQ held within
 * [0.52 BW, 0.48 fs] (so that FREQ > BW/2 and a proper Q always exist),
 * with each notch of a composite BW/n wide. */
static fc_status_t design(fc_notch_t *n, const fc_notch_config_t *cfg, float dt_s)
{
    n->cfg = *cfg;
    n->composite = composite_count(cfg->options);
    if (!(dt_s > 0.0f) || !fc_finitef(dt_s) || !fc_finitef(cfg->freq_hz)
        || !(cfg->bw_hz > 0.0f) || !fc_finitef(cfg->bw_hz) || !fc_finitef(cfg->att_db)) {
        n->cfg.enable = false;
        return FC_ERR_ARG;
    }
    n->dt_s = dt_s;
    const float f0 = fc_constrainf(cfg->freq_hz, 0.52f * cfg->bw_hz,
                                   FC_NOTCH_NYQUIST_FRACTION / dt_s);
    const float half_bw = 0.5f * cfg->bw_hz / (float)n->composite;
    const float r = f0 / (f0 - half_bw); /* octave ratio of the lower -3 dB point */
    n->k = (r * r - 1.0f) / r;           /* 1/Q, Q = r / (r^2 - 1) */
    n->att = powf(10.0f, -cfg->att_db / 40.0f);
    n->spread = cfg->bw_hz / (32.0f * f0);
    n->min_hz = cfg->freq_hz * cfg->fm_ratio;
    return FC_OK;
}

/* ---- one notch's tuning --------------------------------------------------- */

static void gains(fc_notch_filter_t *f)
{
    f->c1 = 1.0f / (1.0f + f->g * (f->g + f->k));
    f->c2 = f->g * f->c1;
    f->c3 = f->g * f->c2;
}

/* Head for centre hz and depth m: at once for a notch that is starting or
 * with no ramp, else linearly over `ramp` samples. */
static void retune(const fc_notch_t *n, fc_notch_filter_t *f, float hz, float m, uint16_t ramp)
{
    if (f->state == FC_NOTCH_FILTER_ON) {
        hz = fc_constrainf(hz, f->center_hz * FC_NOTCH_SLEW_LOWER,
                           f->center_hz / FC_NOTCH_SLEW_LOWER);
    }
    if (!(hz > 0.0f) || !(hz * n->dt_s < 0.5f * 0.999f)) {
        f->state = FC_NOTCH_FILTER_OFF; /* tan() would blow up at Nyquist */
        return;
    }
    if (f->state == FC_NOTCH_FILTER_ON && hz == f->center_hz && m == f->m_to && n->k == f->k_to) {
        return; /* nothing moves: no tan() */
    }
    f->center_hz = hz;
    f->g_to = tanf(FC_PI_F * hz * n->dt_s);
    f->k_to = n->k;
    f->m_to = m;
    if (f->state != FC_NOTCH_FILTER_ON || ramp == 0) {
        f->g = f->g_to;
        f->k = f->k_to;
        f->m = f->m_to;
        f->ramp = 0;
        gains(f);
        if (f->state == FC_NOTCH_FILTER_OFF) {
            f->state = FC_NOTCH_FILTER_START;
        }
        return;
    }
    const float inv = 1.0f / (float)ramp;
    f->dg = (f->g_to - f->g) * inv;
    f->dk = (f->k_to - f->k) * inv;
    f->dm = (f->m_to - f->m) * inv;
    f->ramp = ramp;
}

/* One notch of harmonic `hmul` of source centre `base`, `smul` of a
 * composite (ArduPilot's HarmonicNotchFilter::set_center_frequency). */
static void place(const fc_notch_t *n, fc_notch_filter_t *f, float base, unsigned hmul,
                  float smul, uint16_t ramp)
{
    float hz = base * (float)hmul;
    if (!(hz < FC_NOTCH_NYQUIST_FRACTION / n->dt_s)) {
        f->state = FC_NOTCH_FILTER_OFF;
        return;
    }
    float floor_hz = n->min_hz;
    float a = n->att;
    if (n->cfg.options & FC_NOTCH_OPT_LOW_AS_MIN) {
        floor_hz *= (float)hmul; /* harmonics keep their spacing at the floor */
    } else {
        const float off_hz = floor_hz * FC_NOTCH_OFF_FRACTION;
        if (hz < off_hz) {
            f->state = FC_NOTCH_FILTER_OFF;
            return;
        }
        if (hz < floor_hz) { /* fade to no attenuation: no glitch where it turns off */
            a += (1.0f - a) * (floor_hz - hz) / (floor_hz - off_hz);
        }
    }
    hz = fmaxf(hz, floor_hz) * smul;
    retune(n, f, hz, n->k * (1.0f - a * a), ramp);
}

static uint16_t ramp_samples(const fc_notch_t *n, float interval_s)
{
    const float s = interval_s / n->dt_s + 0.5f;
    if (!(s >= 1.0f)) {
        return 0;
    }
    return (s > 65535.0f) ? (uint16_t)65535u : (uint16_t)s;
}

void fc_notch_set_centers(fc_notch_t *n, unsigned count, const float hz[], float interval_s)
{
    if (!n->cfg.enable) {
        return;
    }
    count = (count > FC_NOTCH_MAX_SOURCES) ? FC_NOTCH_MAX_SOURCES : count;
    const uint16_t ramp = ramp_samples(n, interval_s);
    const float top_hz = FC_NOTCH_NYQUIST_FRACTION / n->dt_s;
    unsigned idx = 0;
    /* Harmonic-major (f1h1, f2h1, ..., f1h2, ...): a full bank drops the highest harmonics. */
    for (unsigned h = 0; h < FC_NOTCH_MAX_HARMONICS; h++) {
        if (!(n->cfg.harmonics & (1u << h))) {
            continue;
        }
        for (unsigned s = 0; s < count; s++) {
            const float base = fc_finitef(hz[s]) ? fc_constrainf(hz[s], 0.0f, top_hz) : 0.0f;
            for (unsigned j = 0; j < n->composite && idx < FC_NOTCH_MAX_FILTERS; j++) {
                place(n, &n->f[idx++], base, h + 1u, spread_mul(n, j), ramp);
            }
        }
    }
    for (unsigned i = idx; i < n->count; i++) {
        n->f[i].state = FC_NOTCH_FILTER_OFF;
    }
    n->count = (uint8_t)idx;
    n->n_sources = (uint8_t)count;
    for (unsigned s = 0; s < count; s++) {
        n->source_hz[s] = hz[s];
    }
}

/* ---- life cycle ------------------------------------------------------------ */

fc_status_t fc_notch_configure(fc_notch_t *n, const fc_notch_config_t *cfg, float dt_s)
{
    const float old_dt_s = n->dt_s;
    const fc_status_t st = design(n, cfg, dt_s);
    if (st != FC_OK) {
        return st;
    }
    if (dt_s != old_dt_s) {
        /* A new sample period is timing, not a move: each tuning at once, states kept. */
        for (unsigned i = 0; i < n->count; i++) {
            fc_notch_filter_t *f = &n->f[i];
            if (f->state != FC_NOTCH_FILTER_OFF && f->center_hz * dt_s < 0.5f * 0.999f) {
                f->g = f->g_to = tanf(FC_PI_F * f->center_hz * dt_s);
                f->k = f->k_to;
                f->m = f->m_to;
                f->ramp = 0;
                gains(f);
            } else {
                f->state = FC_NOTCH_FILTER_OFF;
            }
        }
    }
    const bool fixed = cfg->mode == FC_NOTCH_MODE_FIXED || !(cfg->ref > 0.0f);
    if (fixed || n->n_sources == 0) {
        const float f0 = cfg->freq_hz;
        fc_notch_set_centers(n, 1, &f0, FC_NOTCH_UPDATE_S);
    } else {
        fc_notch_set_centers(n, n->n_sources, n->source_hz, FC_NOTCH_UPDATE_S);
    }
    return FC_OK;
}

fc_status_t fc_notch_init(fc_notch_t *n, const fc_notch_config_t *cfg, float dt_s)
{
    /* Only what is read before it is written: the filters start from their first input. */
    n->dt_s = 0.0f;
    n->count = 0;
    n->n_sources = 0;
    n->countdown = 0;
    n->active = true;
    for (unsigned i = 0; i < FC_NOTCH_MAX_FILTERS; i++) {
        n->f[i].state = FC_NOTCH_FILTER_OFF;
        n->f[i].ramp = 0;
    }
    return fc_notch_configure(n, cfg, dt_s);
}

/* ---- tracking ------------------------------------------------------------- */

/* MODE 1 (AP_Vehicle::update_throttle_notch): FREQ at REF throttle, scaled as
 * rotor speed with sqrt(thrust), never below FREQ x FM_RAT. */
static unsigned throttle_center(const fc_notch_t *n, const fc_notch_inputs_t *in, float hz[],
                                bool *active)
{
    const float thr = fmaxf(0.0f, in->throttle);
    hz[0] = n->cfg.freq_hz * fmaxf(n->cfg.fm_ratio, sqrtf(thr / n->cfg.ref));
    *active = !in->motors_stopped;
    return 1;
}

/* The centres of this update, by MODE (AP_Vehicle::update_dynamic_notch). */
static unsigned centers_now(const fc_notch_t *n, const fc_notch_inputs_t *in, float hz[],
                            bool *active)
{
    const float f0 = n->cfg.freq_hz;
    const bool multi = (n->cfg.options & FC_NOTCH_OPT_MULTI_SOURCE) != 0u;
    *active = true;
    hz[0] = f0;
    if (!(n->cfg.ref > 0.0f)) {
        return 1; /* REF 0: no tracking */
    }
    switch (n->cfg.mode) {
    case FC_NOTCH_MODE_THROTTLE:
        return throttle_center(n, in, hz, active);
    case FC_NOTCH_MODE_ESC:
        if (!multi) {
            hz[0] = fmaxf(f0, in->esc_mean_hz * n->cfg.ref);
            return 1;
        }
        if (in->esc_count == 0) {
            return throttle_center(n, in, hz, active); /* no telemetry yet */
        }
        for (unsigned i = 0; i < in->esc_count && i < FC_NOTCH_MAX_SOURCES; i++) {
            hz[i] = fmaxf(f0, in->esc_hz[i]); /* a silent motor at the floor */
        }
        return in->esc_count;
    case FC_NOTCH_MODE_FFT:
        if (in->fft_count == 0) {
            return 1;
        }
        for (unsigned i = 0; i < in->fft_count && i < FC_NOTCH_MAX_SOURCES; i++) {
            hz[i] = in->fft_hz[i];
        }
        return multi ? in->fft_count : 1u;
    default:
        return 1; /* fixed, and RPM sensors (none fitted) */
    }
}

/* Bypassed notches restart from the input when they come back (ArduPilot
 * resets an inactive notch every sample, so its first output is its input). */
static void set_active(fc_notch_t *n, bool active)
{
    if (active == n->active) {
        return;
    }
    n->active = active;
    for (unsigned i = 0; i < n->count; i++) {
        if (n->f[i].state == FC_NOTCH_FILTER_ON) {
            n->f[i].state = FC_NOTCH_FILTER_START;
        }
    }
}

void fc_notch_track(fc_notch_t *n, const fc_notch_inputs_t *in, float tick_s)
{
    if (!n->cfg.enable || !(tick_s > 0.0f)) {
        return;
    }
    if (n->countdown > 1) {
        n->countdown--;
        return;
    }
    unsigned ticks = 1;
    if (!(n->cfg.options & FC_NOTCH_OPT_LOOP_RATE)) {
        const float t = FC_NOTCH_UPDATE_S / tick_s + 0.5f;
        ticks = (t < 1.0f) ? 1u : ((t > 255.0f) ? 255u : (unsigned)t);
    }
    n->countdown = (uint8_t)ticks;
    float hz[FC_NOTCH_MAX_SOURCES];
    bool active = true;
    const unsigned count = centers_now(n, in, hz, &active);
    set_active(n, active);
    fc_notch_set_centers(n, count, hz, (float)ticks * tick_s);
}

/* ---- the sample path -------------------------------------------------------- */

/* One trapezoidal SVF step (Simper): band-pass v1 from the two integrator
 * states; the notch is the input minus k (1 - A^2) times the band-pass. */
static inline float svf(fc_notch_filter_t *f, int ax, float x)
{
    const float v3 = x - f->ic2[ax];
    const float v1 = f->c1 * f->ic1[ax] + f->c2 * v3;
    const float v2 = f->ic2[ax] + f->c2 * f->ic1[ax] + f->c3 * v3;
    f->ic1[ax] = 2.0f * v1 - f->ic1[ax];
    f->ic2[ax] = 2.0f * v2 - f->ic2[ax];
    return x - f->m * v1;
}

static inline void ramp_step(fc_notch_filter_t *f)
{
    if (--f->ramp == 0) { /* land exactly on the target */
        f->g = f->g_to;
        f->k = f->k_to;
        f->m = f->m_to;
    } else {
        f->g += f->dg;
        f->k += f->dk;
        f->m += f->dm;
    }
    gains(f);
}

void fc_notch_apply(fc_notch_t *n, float v[3])
{
    if (!n->active) {
        return;
    }
    for (unsigned i = 0; i < n->count; i++) {
        fc_notch_filter_t *f = &n->f[i];
        if (f->state == FC_NOTCH_FILTER_OFF) {
            continue;
        }
        if (f->state == FC_NOTCH_FILTER_START) {
            /* The steady state of a constant input: band-pass 0, low-pass = input. */
            for (int ax = 0; ax < 3; ax++) {
                f->ic1[ax] = 0.0f;
                f->ic2[ax] = v[ax];
            }
            f->state = FC_NOTCH_FILTER_ON;
        }
        if (f->ramp != 0) {
            ramp_step(f);
        }
        v[0] = svf(f, 0, v[0]);
        v[1] = svf(f, 1, v[1]);
        v[2] = svf(f, 2, v[2]);
    }
}
