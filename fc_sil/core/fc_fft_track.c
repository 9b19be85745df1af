/*
 * fc_fft_track.c - a frame's peaks into tracked noise frequencies, and what the
 * notch, the log and hover learning read (AP_GyroFFT's calculate_noise,
 * calculate_tracking_peaks, calculate_filtered_noise, get_tracked_noise_peak,
 * get_weighted_noise_center_freq_hz, update_freq_hover; rewritten, see fc_fft.h).
 */
#include "fc_fft_peaks.h"

#include "fc_math.h"

#define FC_FFT_MAX_MISSED 5u          /* FFT_MAX_MISSED_UPDATES (AP_HAL/DSP.h) */
#define FC_FFT_FIT_ENERGY_MULT 200.0f /* FFT_HARMONIC_FIT_MULT: energies too far apart: no fit */
#define FC_FFT_NONE 3                 /* no peak (FrequencyPeak::NONE) */

typedef struct frame_peaks {
    float freq_hz[FC_FFT_MAX_PEAKS];
    float snr_db[FC_FFT_MAX_PEAKS];
    bool valid[FC_FFT_MAX_PEAKS];
} frame_peaks_t;

static void frame_peaks(fc_fft_t *f, frame_peaks_t *fp)
{
    for (int i = 0; i < FC_FFT_MAX_PEAKS; i++) {
        fp->valid[i] = false;
        fp->freq_hz[i] = f->cfg.min_hz;
        fp->snr_db[i] = 0.0f;
        if (i >= f->found_n) {
            continue;
        }
        fc_fft_found_t *pk = &f->found[i];
        pk->width_hz *= f->bin_hz;
        pk->freq_hz = fc_fft_peak_freq_hz(f, pk);
        fp->snr_db[i] = fc_fft_peak_snr_db(f, pk);
        /* no peak counts until every axis has its noise reference, as ArduPilot */
        if (f->needs_calibration == 0 && fc_finitef(pk->power)
            && fp->snr_db[i] > f->cfg.snr_ref_db) {
            fp->valid[i] = true;
            fp->freq_hz[i] = fc_constrainf(pk->freq_hz, f->cfg.min_hz, f->cfg.max_hz);
        }
    }
}

/* AP_GyroFFT::update_ref_energy's counters (the sums are added in the POWER phase). */
static void reference_bookkeeping(fc_fft_t *f)
{
    const uint8_t a = f->axis;
    if (!((f->needs_calibration >> a) & 1u)) {
        return;
    }
    if (f->skip_frames == 0 && f->calib_frames[a] > 0) {
        if (--f->calib_frames[a] == 0) {
            f->needs_calibration &= (uint8_t)~(1u << a);
        }
    } else if (f->skip_frames > 0) {
        f->skip_frames--;
    }
}

/* One slot's new values: frequency through a median of three then a low-pass (a spike
 * from another peak must not pull the notch), energy and width through a low-pass. */
static void track_set(fc_fft_t *f, fc_fft_track_t *t, float energy, float bw_hz, float freq_hz)
{
    t->median[t->median_n % 3u] = freq_hz;
    if (t->median_n == 0) {
        t->median[1] = t->median[2] = freq_hz;
        t->freq_hz = freq_hz;
        t->bw_hz = bw_hz;
        t->energy = energy;
    }
    t->median_n = (uint8_t)(t->median_n % 3u + 1u);
    const float a = t->median[0], b = t->median[1], c = t->median[2];
    const float med = fmaxf(fminf(a, b), fminf(fmaxf(a, b), c));
    t->prev_freq_hz = t->freq_hz;
    t->freq_hz += f->alpha_freq * (med - t->freq_hz);
    t->bw_hz += f->alpha_energy * (bw_hz - t->bw_hz);
    t->energy += f->alpha_energy * (energy - t->energy);
}

/* calculate_filtered_noise: slot `target` takes the frame's peak `source`; a missing
 * peak keeps the old values for FC_FFT_MAX_MISSED frames, then falls to FFT_MINHZ. */
static bool update_slot(fc_fft_t *f, int target, int source, const frame_peaks_t *fp)
{
    fc_fft_track_t *t = &f->track[f->axis][target];
    const bool exists = source < f->found_n;
    if (exists && fp->valid[source]) {
        const fc_fft_found_t *pk = &f->found[source];
        track_set(f, t, fc_fft_peak_energy(f, pk), pk->width_hz, fp->freq_hz[source]);
        t->missed = 0;
        return true;
    }
    if (t->missed++ < FC_FFT_MAX_MISSED) {
        return true; /* a synthetic peak: the previous values stand */
    }
    const float e = exists ? fc_fft_peak_energy(f, &f->found[source]) : 0.0f;
    track_set(f, t, e, f->bw_hover_hz, f->cfg.min_hz);
    return false;
}

/* The frame's valid peak nearest slot `target`'s tracked frequency, not in `ignore`. */
static int closest_peak(const fc_fft_t *f, const frame_peaks_t *fp, int target, unsigned ignore)
{
    const float cur = f->track[f->axis][target].freq_hz;
    int best = target;
    float best_d = fp->valid[target] ? fabsf(fp->freq_hz[target] - cur) : INFINITY;
    for (int i = 0; i < FC_FFT_MAX_PEAKS; i++) {
        const float d = fp->valid[i] ? fabsf(fp->freq_hz[i] - cur) : INFINITY;
        if (d < best_d && !(ignore & (1u << i))) {
            best = i;
            best_d = d;
        }
    }
    return (ignore & (1u << best)) ? FC_FFT_NONE : best;
}

/* update_snr_values: each slot shows the SNR of the frame's peak of its rank (strongest
 * first), whichever peak the slot took; FTN1's SnX..Z is the strongest's. */
static void record_snr(fc_fft_t *f, const frame_peaks_t *fp)
{
    for (int i = 0; i < FC_FFT_MAX_PEAKS; i++) {
        f->slot_snr_db[f->axis][i] = fp->snr_db[i];
    }
    f->snr_db[f->axis] = fp->snr_db[FC_FFT_CENTER];
}

/* calculate_tracking_peaks: the peaks come strongest first, but two of similar strength
 * swap places from frame to frame; a slot follows the peak nearest its own frequency,
 * for a few frames at a time (the distorted-cycle budget), so the tracks stay continuous. */
static int track_peaks(fc_fft_t *f, const frame_peaks_t *fp)
{
    const uint8_t a = f->axis;
    const int c = closest_peak(f, fp, FC_FFT_CENTER, 0u);
    const int l = closest_peak(f, fp, FC_FFT_LOWER, 1u << c);
    const int u = closest_peak(f, fp, FC_FFT_UPPER, (1u << c) | (1u << l));
    int n = 0;
    const bool swapped = c != FC_FFT_CENTER || l != FC_FFT_LOWER || u != FC_FFT_UPPER;
    if (f->distorted[a] > 0 && swapped) {
        n += (l != FC_FFT_NONE) && update_slot(f, FC_FFT_LOWER, l, fp);
        n += (u != FC_FFT_NONE) && update_slot(f, FC_FFT_UPPER, u, fp);
        n += (c != FC_FFT_NONE) && update_slot(f, FC_FFT_CENTER, c, fp);
        record_snr(f, fp);
        f->distorted[a]--;
        return n;
    }
    n += update_slot(f, FC_FFT_LOWER, FC_FFT_LOWER, fp);
    n += update_slot(f, FC_FFT_UPPER, FC_FFT_UPPER, fp);
    n += update_slot(f, FC_FFT_CENTER, FC_FFT_CENTER, fp);
    record_snr(f, fp);
    if (f->distorted[a] < FC_FFT_MAX_MISSED) {
        f->distorted[a]++;
    }
    return n;
}

/* The strongest peak may be a harmonic of a lower one (on larger frames the second
 * harmonic often carries more energy): then the lower one is the fundamental. */
static void harmonic_fit(fc_fft_t *f, int peaks)
{
    const uint8_t a = f->axis;
    const fc_fft_track_t *t = f->track[a];
    uint8_t tracked = FC_FFT_CENTER;
    if (peaks > 1 && f->tracked_peaks > 1 && t[FC_FFT_CENTER].freq_hz != 0.0f) {
        const float fc = t[FC_FFT_CENTER].freq_hz, ec = t[FC_FFT_CENTER].energy;
        if (fc > t[FC_FFT_LOWER].freq_hz && ec < t[FC_FFT_LOWER].energy * FC_FFT_FIT_ENERGY_MULT) {
            tracked = FC_FFT_LOWER;
        } else if (peaks > 2 && fc > t[FC_FFT_UPPER].freq_hz
                   && ec < t[FC_FFT_UPPER].energy * FC_FFT_FIT_ENERGY_MULT) {
            tracked = FC_FFT_UPPER;
        }
    }
    f->tracked_slot[a] = tracked;
    if (tracked == FC_FFT_CENTER) {
        f->harmonic_fit[a] = 100.0f;
        return;
    }
    const float fc = t[FC_FFT_CENTER].freq_hz;
    const float fit = 100.0f * fabsf(fc - t[tracked].freq_hz * f->harmonic_mult) / fc;
    if (fc_finitef(fit)) {
        f->harmonic_fit[a] += f->alpha_fit * (fit - f->harmonic_fit[a]);
    }
}

void fc_fft_finish_frame(fc_fft_t *f)
{
    const uint8_t a = f->axis;
    reference_bookkeeping(f);
    frame_peaks_t fp;
    frame_peaks(f, &fp);
    const int n = track_peaks(f, &fp);
    f->peaks[a] = (uint8_t)n;
    f->good_at[a] = n > 0 ? f->pushed + 1u : 0u;
    f->output_at[a] = f->pushed;
    harmonic_fit(f, n);
}
