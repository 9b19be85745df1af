/*
 * fc_fft_output.c - what the in-flight FFT hands out: the notch's MODE 4 frequencies,
 * FTN1/FTN2, the calibration text's figures, the noise at a given frequency, and hover
 * learning (AP_GyroFFT's get_*, pre_arm_check's text, has_noise_at_frequency_hz and
 * update_freq_hover, rewritten; see fc_fft.h). Reads only, but for hover learning: the
 * analysis itself never depends on these.
 */
#include "fc_fft_peaks.h"

#include "fc_math.h"

#define FC_FFT_MAX_MISSED 5u   /* FFT_MAX_MISSED_UPDATES: frames an axis may go without a peak */
#define FC_FFT_PEAK_ROLL 4u    /* FFT_HMNC_PEAK: roll axis only */
#define FC_FFT_PEAK_PITCH 5u   /* FFT_HMNC_PEAK: pitch axis only */
#define FC_FFT_HOVER_TC_S 10.0f /* hover learning's time constant (update_freq_hover) [s] */

/* An axis is healthy while its last frame with a peak is at most FC_FFT_MAX_MISSED
 * frame times old (AP_GyroFFT::update). */
static bool axis_healthy(const fc_fft_t *f, int a)
{
    return f->good_at[a] != 0
           && (uint32_t)(f->pushed + 1u - f->good_at[a]) <= (uint32_t)f->hop * FC_FFT_MAX_MISSED;
}

/* FH: the peaks of the healthy roll/pitch axes' latest frames, at most the notches fed
 * (at least one, so the FFT reports a frequency with no notch on it). ArduPilot takes the
 * latest frame of any axis, so a quiet yaw axis makes its health flicker; here yaw,
 * which the frequency never uses, does not count. */
static uint8_t health_now(const fc_fft_t *f)
{
    uint8_t peaks = 0;
    for (int a = 0; a < 2; a++) {
        if (axis_healthy(f, a) && f->peaks[a] > peaks) {
            peaks = f->peaks[a];
        }
    }
    const uint8_t notches = f->cfg.notches > 1 ? f->cfg.notches : 1;
    return peaks < notches ? peaks : notches;
}

/* No healthy peak: the hover frequency scaled by thrust (sqrt: rotor speed goes with
 * the square root of thrust). */
static float throttle_estimate(const fc_fft_t *f, float throttle_out)
{
    const float r = throttle_out / f->thr_ref;
    const float est = f->cfg.min_hz * fmaxf(1.0f, sqrtf(fc_finitef(r) && r > 0.0f ? r : 0.0f));
    return fc_constrainf(est, f->cfg.min_hz, f->cfg.max_hz);
}

/* A slot's frequency on one axis, moved from its previous to its latest value over a
 * frame's time so the notch does not step at the FFT's output rate. */
static float slewed(const fc_fft_t *f, int slot, int a)
{
    const fc_fft_track_t *t = &f->track[a][slot];
    const float s = fminf(1.0f, (float)(f->pushed - f->output_at[a]) / (float)f->hop);
    return t->prev_freq_hz + (t->freq_hz - t->prev_freq_hz) * s;
}

/* Roll and pitch weighted by energy (yaw's low-frequency noise is left out, as ArduPilot). */
static float weighted(float ex, float ey, float vx, float vy)
{
    if (fc_finitef(ex) && fc_finitef(ey) && ex != 0.0f && ey != 0.0f) {
        return (vx * ex + vy * ey) / (ex + ey);
    }
    return (vx + vy) * 0.5f;
}

static int tracked_peak(const fc_fft_t *f)
{
    const uint8_t hp = f->cfg.hmnc_peak;
    const float thr = f->cfg.hmnc_fit_pct;
    if (hp > FC_FFT_MAX_PEAKS) {
        if (hp == FC_FFT_PEAK_ROLL && f->harmonic_fit[0] < thr) {
            return f->tracked_slot[0];
        }
        if (hp == FC_FFT_PEAK_PITCH && f->harmonic_fit[1] < thr) {
            return f->tracked_slot[1];
        }
        return FC_FFT_CENTER;
    }
    if (hp > 0) {
        return hp - 1;
    }
    /* both roll and pitch must see the harmonic relation before the lower peak is used */
    if (f->harmonic_fit[0] < thr && f->harmonic_fit[1] < thr) {
        return f->tracked_slot[0];
    }
    return FC_FFT_CENTER;
}

static float slot_freq_hz(const fc_fft_t *f, int slot)
{
    if (!axis_healthy(f, 0) || f->cfg.hmnc_peak == FC_FFT_PEAK_PITCH) {
        return slewed(f, slot, 1);
    }
    if (!axis_healthy(f, 1) || f->cfg.hmnc_peak == FC_FFT_PEAK_ROLL) {
        return slewed(f, slot, 0);
    }
    return weighted(f->track[0][slot].energy, f->track[1][slot].energy, slewed(f, slot, 0),
                    slewed(f, slot, 1));
}

float fc_fft_center_freq_hz(const fc_fft_t *f, float throttle_out)
{
    if (!f->active) {
        return f->cfg.min_hz;
    }
    if (health_now(f) == 0) {
        return throttle_estimate(f, throttle_out);
    }
    return slot_freq_hz(f, tracked_peak(f));
}

unsigned fc_fft_center_freqs_hz(const fc_fft_t *f, float throttle_out, float *freqs_hz,
                                unsigned max_n)
{
    if (max_n == 0) {
        return 0;
    }
    const uint8_t h = f->active ? health_now(f) : 0;
    if (h == 0) {
        freqs_hz[0] = f->active ? throttle_estimate(f, throttle_out) : f->cfg.min_hz;
        return 1;
    }
    const unsigned n = h < max_n ? h : max_n;
    for (unsigned i = 0; i < n; i++) {
        freqs_hz[i] = slot_freq_hz(f, (int)i);
    }
    return n;
}

unsigned fc_fft_notch_freqs(const fc_fft_t *f, float throttle_out,
                            float freqs_hz[FC_FFT_MAX_PEAKS])
{
    freqs_hz[0] = fc_fft_center_freq_hz(f, throttle_out);
    const uint8_t h = f->active ? health_now(f) : 0;
    if (h <= 1) {
        return 1;
    }
    const int fundamental = tracked_peak(f);
    unsigned n = 1;
    for (int slot = 0; slot < FC_FFT_MAX_PEAKS && n < h; slot++) {
        if (slot != fundamental) {
            freqs_hz[n++] = slot_freq_hz(f, slot);
        }
    }
    return n;
}

static float weighted_bw_hz(const fc_fft_t *f)
{
    const int p = tracked_peak(f);
    return weighted(f->track[0][p].energy, f->track[1][p].energy, f->track[0][p].bw_hz,
                    f->track[1][p].bw_hz);
}

void fc_fft_update_freq_hover(fc_fft_t *f, float dt_s, float throttle_out)
{
    if (!f->active || !(dt_s > 0.0f) || !fc_finitef(throttle_out)) {
        return;
    }
    const float k = dt_s / (FC_FFT_HOVER_TC_S + dt_s);
    const fc_fft_config_t *c = &f->cfg;
    f->freq_hover_hz = fc_constrainf(
        f->freq_hover_hz + k * (fc_fft_center_freq_hz(f, throttle_out) - f->freq_hover_hz),
        c->min_hz, c->max_hz);
    f->bw_hover_hz = fc_constrainf(f->bw_hover_hz + k * (weighted_bw_hz(f) - f->bw_hover_hz),
                                   0.0f, c->max_hz * 0.5f);
    /* the throttle at which the rotors would turn at FFT_MINHZ */
    const float ratio = c->min_hz / f->freq_hover_hz;
    f->thr_ref = fc_constrainf(f->thr_ref + k * (throttle_out * ratio * ratio - f->thr_ref),
                               0.01f, 0.9f);
    f->learned = true;
}

void fc_fft_ftn1(const fc_fft_t *f, float throttle_out, fc_fft_ftn1_t *out)
{
    out->pk_avg_hz = fc_fft_center_freq_hz(f, throttle_out);
    out->bw_avg_hz = f->active ? weighted_bw_hz(f) : 0.0f;
    for (int a = 0; a < FC_FFT_AXES; a++) {
        out->snr_db[a] = f->snr_db[a];
        out->fit_pct[a] = f->harmonic_fit[a];
    }
    out->health = f->active ? health_now(f) : 0;
    out->cycle_us = f->active ? (uint32_t)((float)f->frame_samples * 1e6f / f->fs_hz) : 0u;
}

void fc_fft_ftn2(const fc_fft_t *f, unsigned slot, float pk_hz[3], float bw_hz[3],
                 float energy[3])
{
    const unsigned s = slot < FC_FFT_MAX_PEAKS ? slot : FC_FFT_CENTER;
    for (int a = 0; a < FC_FFT_AXES; a++) {
        pk_hz[a] = f->track[a][s].freq_hz;
        bw_hz[a] = f->track[a][s].bw_hz;
        energy[a] = f->track[a][s].energy;
    }
}

void fc_fft_calibration(const fc_fft_t *f, fc_fft_calibration_t *out)
{
    if (!f->active) {
        *out = (fc_fft_calibration_t){0.0f, 0.0f, 0.0f};
        return;
    }
    /* ArduPilot holds the sample rate and a frame's time in whole units (uint16 Hz and ms,
     * the latter truncated), so its output rate is 3000 / whole ms, not fs * 3 / hop:
     * 1 kHz with 16-sample frames reports 187.5 Hz, and 1.2 kHz 230.8 Hz (13 ms) */
    const unsigned fs_hz = (unsigned)lrintf(f->fs_hz);
    const unsigned frame_ms = fs_hz > 0u ? (unsigned)f->hop * 1000u / fs_hz : 0u;
    out->sample_khz = (float)fs_hz * 0.001f;
    out->half_bin_hz = f->bin_hz * 0.5f;
    out->output_hz = frame_ms > 0u ? 1000.0f * (float)FC_FFT_AXES / (float)frame_ms : INFINITY;
}

float fc_fft_noise_at_hz(const fc_fft_t *f, float hz)
{
    if (!f->active) {
        return 0.0f;
    }
    float snr_db = 0.0f;
    for (unsigned p = 0; p < f->tracked_peaks && p < FC_FFT_MAX_PEAKS; p++) {
        for (int a = 0; a < FC_FFT_AXES; a++) {
            const float at_hz = f->track[a][p].freq_hz;
            /* one bin either side, and only where the axis has a live peak */
            if (axis_healthy(f, a) && fabsf(at_hz - hz) < f->bin_hz
                && f->slot_snr_db[a][p] > snr_db) {
                snr_db = f->slot_snr_db[a][p];
            }
        }
    }
    return snr_db;
}
