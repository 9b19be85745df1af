/*
 * fc_fft.c - the in-flight FFT's engine: configuration, the gyro history, and the
 * frame pipeline spread over IMU steps (see fc_fft.h). The peaks, tracking and the
 * outputs are in fc_fft_peaks.c.
 *
 * One frame, one axis, in phases; each fc_fft_step spends at most FC_FFT_STEP_UNITS:
 *   LOAD   window the samples and store them bit-reversed (1 unit per sample)
 *   BFLY   the radix-2 butterflies, stage after stage (1 unit per butterfly)
 *   POWER  |X|^2 per bin, averaging and the noise reference (1 unit per bin)
 *   SCAN   the three strongest local maxima (1 unit per bin)
 *   WIDTH  each peak's -FFT_ATT_REF dB edges (1 unit per bin walked)
 *   FINISH interpolation, SNR, tracking, harmonic fit (a fixed handful)
 */
#include "fc_fft.h"

#include <string.h>

#include "fc_fft_peaks.h"
#include "fc_math.h"

/* ArduPilot keeps gyro windows in int16 counts of a +-2000 deg/s gyro
 * (AP_InertialSensor _gyro_raw_sampling_multiplier = INT16_MAX / radians(2000)). */
#define FC_FFT_COUNTS_PER_RAD_S (32767.0f / (2000.0f * FC_DEG_TO_RAD_F))
/* AP_GyroFFT: a frame is at least 16 samples (bounds the output rate). */
#define FC_FFT_MIN_HOP 16u
/* MAXHZ may not reach Nyquist (AP_GyroFFT::update_parameters). */
#define FC_FFT_MAX_FRACTION_OF_FS 0.48f
/* Low-pass corners of the tracked values, as fractions of the output rate (AP_GyroFFT::init):
 * frequency 0.48, energy and bandwidth 0.25; the harmonic fit at most 15 Hz. */
#define FC_FFT_FREQ_CORNER 0.48f
#define FC_FFT_ENERGY_CORNER 0.25f
#define FC_FFT_FIT_CORNER_HZ 15.0f

static uint16_t round_pow2(float x)
{
    const float l = (x > 1.0f) ? log2f(x) : 0.0f;
    return (uint16_t)(1u << (unsigned)lrintf(l));
}

/* alpha of a first-order low-pass at corner_hz sampled at rate_hz (ArduPilot DigitalLPF). */
static float lpf_alpha(float rate_hz, float corner_hz)
{
    const float dt = 1.0f / rate_hz;
    return dt / (dt + 1.0f / (FC_TWO_PI_F * corner_hz));
}

/* Tables that depend on the window size only: Hann window (ArduPilot's, periodic in
 * N - 1), twiddles and the bit-reversal permutation. */
static void build_tables(fc_fft_t *f)
{
    const uint16_t n = f->n;
    float sum = 0.0f;
    for (uint16_t i = 0; i < n; i++) {
        f->hann[i] = 0.5f - 0.5f * cosf(FC_TWO_PI_F * (float)i / ((float)n - 1.0f));
        sum += f->hann[i];
        uint16_t r = 0;
        for (uint8_t b = 0; b < f->log2n; b++) {
            r = (uint16_t)(r | (((i >> b) & 1u) << (f->log2n - 1u - b)));
        }
        f->bitrev[i] = r;
    }
    /* 2 / (sum w)^2 (ArduPilot: the inverse effective noise bandwidth): a sine of
     * amplitude A on a bin centre shows A^2 / 2 in that bin */
    f->window_scale = 2.0f / (sum * sum);
    for (uint16_t k = 0; k < n / 2u; k++) {
        f->cos_t[k] = cosf(FC_TWO_PI_F * (float)k / (float)n);
        f->sin_t[k] = sinf(FC_TWO_PI_F * (float)k / (float)n);
    }
}

/* The notch's harmonics decide how many peaks are tracked and what "harmonic" means
 * (AP_GyroFFT::init): popcount of the bitmask, and second set harmonic / first. */
static void harmonics_setup(fc_fft_t *f, const fc_fft_config_t *cfg)
{
    const unsigned h = cfg->harmonics != 0 ? cfg->harmonics : 3u;
    unsigned count = 0, first = 0, second = 0;
    for (unsigned i = 0; i < 16u; i++) {
        if (h & (1u << i)) {
            count++;
            if (first == 0) {
                first = i + 1u;
            } else if (second == 0) {
                second = i + 1u;
            }
        }
    }
    if (cfg->notches > count) {
        count = cfg->notches;
    }
    f->tracked_peaks = (uint8_t)(count < 1u ? 1u : (count > 3u ? 3u : count));
    f->harmonic_mult = (second != 0) ? (float)second / (float)first : 2.0f;
}

static void derive(fc_fft_t *f, const fc_fft_config_t *cfg, float sample_hz, float loop_hz)
{
    uint16_t n = round_pow2((float)cfg->window_size);
    n = n < FC_FFT_MIN_WINDOW ? FC_FFT_MIN_WINDOW : (n > FC_FFT_MAX_WINDOW ? FC_FFT_MAX_WINDOW : n);
    f->n = n;
    f->log2n = (uint8_t)lrintf(log2f((float)n));
    const float olap = fc_constrainf(cfg->window_overlap, 0.0f, 0.9f);
    uint16_t hop = round_pow2((1.0f - olap) * (float)n);
    f->hop = hop < FC_FFT_MIN_HOP ? (uint16_t)FC_FFT_MIN_HOP : hop;
    f->decim = 1;
    if (cfg->sample_mode > 0 && loop_hz > 0.0f) {
        /* loop-rate sampling: the loop's own decimation of the gyro, times the mode */
        const long per_loop = lrintf(sample_hz / loop_hz);
        f->decim = (uint16_t)((per_loop < 1 ? 1 : per_loop) * cfg->sample_mode);
    }
    f->fs_hz = sample_hz / (float)f->decim;
    f->bin_hz = f->fs_hz / (float)n;
    const float max_hz = fminf(cfg->max_hz, f->fs_hz * FC_FFT_MAX_FRACTION_OF_FS);
    f->start_bin = (uint16_t)fmaxf(floorf(cfg->min_hz / f->bin_hz), 1.0f);
    f->end_bin = (uint16_t)fminf(ceilf(max_hz / f->bin_hz), (float)(n / 2u));
    f->att_cutoff = powf(10.0f, -cfg->att_ref_db * 0.1f);
    const float out_hz = f->fs_hz / (float)f->hop;
    f->alpha_freq = lpf_alpha(out_hz, out_hz * FC_FFT_FREQ_CORNER);
    f->alpha_energy = lpf_alpha(out_hz, out_hz * FC_FFT_ENERGY_CORNER);
    f->alpha_fit = lpf_alpha(out_hz, fminf(out_hz * FC_FFT_FREQ_CORNER, FC_FFT_FIT_CORNER_HZ));
    harmonics_setup(f, cfg);
}

/* Clear the history, the frame pipeline and the tracks; the noise reference is learned
 * anew (AP_GyroFFT: skip window/hop * 3 frames, then average window/hop * 2 per axis). */
static void restart(fc_fft_t *f)
{
    memset(f->ring, 0, sizeof f->ring);
    memset(f->frames, 0, sizeof f->frames);
    memset(f->avg, 0, sizeof f->avg);
    memset(f->ref_energy, 0, sizeof f->ref_energy);
    memset(f->track, 0, sizeof f->track);
    memset(f->frame_slot, 0, sizeof f->frame_slot);
    memset(f->slot_snr_db, 0, sizeof f->slot_snr_db);
    f->pushed = 0;
    f->decim_count = 0;
    f->phase = FC_FFT_PHASE_IDLE;
    f->axis = 0;
    f->cursor = 0;
    const uint16_t per_window = (uint16_t)(f->n / f->hop);
    f->skip_frames = (uint16_t)(per_window * FC_FFT_AXES);
    for (int a = 0; a < FC_FFT_AXES; a++) {
        f->next_start[a] = 0;
        f->decim_sum[a] = 0.0f;
        f->calib_frames[a] = (uint16_t)(per_window * 2u);
        f->tracked_slot[a] = FC_FFT_CENTER;
        f->harmonic_fit[a] = 100.0f;
        f->snr_db[a] = 0.0f;
        f->good_at[a] = 0;
        f->output_at[a] = 0;
        f->peaks[a] = 0;
        f->distorted[a] = 0;
        for (int p = 0; p < FC_FFT_MAX_PEAKS; p++) {
            f->track[a][p].freq_hz = f->cfg.min_hz;
            f->track[a][p].prev_freq_hz = f->cfg.min_hz;
        }
    }
    f->needs_calibration = 0x7u;
    f->frames_done = 0;
    f->frame_samples = 0;
}

void fc_fft_configure(fc_fft_t *f, const fc_fft_config_t *cfg, float sample_hz, float loop_hz)
{
    const uint16_t old_n = f->n, old_hop = f->hop;
    const float old_fs_hz = f->fs_hz;
    const bool was_active = f->active;
    const uint8_t old_frames = f->cfg.num_frames;
    /* FFT_FREQ_HOVER, FFT_BW_HOVER, FFT_THR_REF are ArduPilot's learned state itself: a new
     * value set from outside replaces what was learned */
    const bool new_learned = !was_active || cfg->freq_hover_hz != f->cfg.freq_hover_hz
                             || cfg->bw_hover_hz != f->cfg.bw_hover_hz
                             || cfg->thr_ref != f->cfg.thr_ref;
    f->cfg = *cfg;
    if (f->cfg.num_frames > 0) {
        f->cfg.num_frames = (uint8_t)(cfg->num_frames < 2 ? 2
                                      : (cfg->num_frames > FC_FFT_MAX_FRAMES ? FC_FFT_MAX_FRAMES
                                                                             : cfg->num_frames));
    }
    f->active = cfg->enable && sample_hz > 0.0f && fc_finitef(sample_hz);
    if (!f->active) {
        return;
    }
    derive(f, cfg, sample_hz, loop_hz);
    if (old_n != f->n) {
        build_tables(f);
    }
    if (new_learned) {
        f->freq_hover_hz = cfg->freq_hover_hz;
        f->bw_hover_hz = cfg->bw_hover_hz;
        f->thr_ref = cfg->thr_ref;
        f->learned = false;
    }
    if (!was_active || old_n != f->n || old_hop != f->hop || old_frames != f->cfg.num_frames
        || fabsf(old_fs_hz - f->fs_hz) > 0.01f * f->fs_hz) {
        restart(f);
    }
}

void fc_fft_init(fc_fft_t *f, const fc_fft_config_t *cfg, float sample_hz, float loop_hz)
{
    f->active = false;
    f->n = 0;
    f->hop = 0;
    f->fs_hz = 0.0f;
    f->cfg.num_frames = 0;
    f->last_units = 0;
    f->max_units = 0;
    /* the motor-noise check's filters and clock run from boot (AP_Vehicle's), not per restart */
    memset(&f->esc_noise, 0, sizeof f->esc_noise);
    fc_fft_configure(f, cfg, sample_hz, loop_hz);
}

void fc_fft_push(fc_fft_t *f, const float gyro_frd_rad_s[3])
{
    if (!f->active || !fc_finite3(gyro_frd_rad_s)) {
        return;
    }
    for (int a = 0; a < FC_FFT_AXES; a++) {
        f->decim_sum[a] += gyro_frd_rad_s[a];
    }
    if (++f->decim_count < f->decim) {
        return;
    }
    const float k = FC_FFT_COUNTS_PER_RAD_S / (float)f->decim;
    const uint32_t at = f->pushed & (FC_FFT_RING - 1u);
    for (int a = 0; a < FC_FFT_AXES; a++) {
        f->ring[a][at] = f->decim_sum[a] * k;
        f->decim_sum[a] = 0.0f;
    }
    f->decim_count = 0;
    f->pushed++;
}

/* Start the next axis' frame when its window is complete. An axis that fell more than
 * half a hop behind jumps to the newest window (AP_GyroFFT::run_cycle drops samples). */
static bool frame_begin(fc_fft_t *f)
{
    const uint8_t a = f->axis;
    uint32_t start = f->next_start[a];
    if ((uint32_t)(f->pushed - start) < f->n) {
        return false;
    }
    if ((uint32_t)(f->pushed - start) > (uint32_t)f->n + f->hop / 2u) {
        start = f->pushed - f->n;
    }
    f->frame_start = start;
    f->next_start[a] = start + f->hop;
    f->frame_begun_at = f->pushed;
    f->phase = FC_FFT_PHASE_LOAD;
    f->cursor = 0;
    return true;
}

static unsigned phase_load(fc_fft_t *f, unsigned budget)
{
    const float *x = f->ring[f->axis];
    unsigned done = 0;
    while (done < budget && f->cursor < f->n) {
        const uint32_t i = f->cursor++;
        const uint16_t j = f->bitrev[i];
        f->re[j] = x[(f->frame_start + i) & (FC_FFT_RING - 1u)] * f->hann[i];
        f->im[j] = 0.0f;
        done++;
    }
    if (f->cursor >= f->n) {
        f->phase = FC_FFT_PHASE_BFLY;
        f->cursor = 0;
    }
    return done;
}

/* Butterfly b of the whole transform: stage s = b / (n/2), and within it j = b % (n/2)
 * in groups of half-size h = 2^s; X[i0] +- W^(k n / 2h) X[i1] with W = exp(-2 pi i / n)
 * (numpy's sign). Powers of two make every division a shift. */
static unsigned phase_bfly(fc_fft_t *f, unsigned budget)
{
    const uint32_t half = f->n / 2u;
    const uint32_t total = half * f->log2n;
    const uint8_t half_log2 = (uint8_t)(f->log2n - 1u);
    unsigned done = 0;
    while (done < budget && f->cursor < total) {
        const uint32_t b = f->cursor++;
        const uint32_t s = b >> half_log2, j = b & (half - 1u);
        const uint32_t h = 1u << s;
        const uint32_t k = j & (h - 1u);
        const uint32_t i0 = ((j >> s) << (s + 1u)) + k, i1 = i0 + h;
        const uint32_t t = k << (half_log2 - s);
        const float wr = f->cos_t[t], wi = -f->sin_t[t];
        const float xr = f->re[i1] * wr - f->im[i1] * wi;
        const float xi = f->re[i1] * wi + f->im[i1] * wr;
        f->re[i1] = f->re[i0] - xr;
        f->im[i1] = f->im[i0] - xi;
        f->re[i0] += xr;
        f->im[i0] += xi;
        done++;
    }
    if (f->cursor >= total) {
        f->phase = FC_FFT_PHASE_POWER;
        f->cursor = 0;
    }
    return done;
}

static unsigned run_phase(fc_fft_t *f, unsigned budget)
{
    switch (f->phase) {
    case FC_FFT_PHASE_LOAD:
        return phase_load(f, budget);
    case FC_FFT_PHASE_BFLY:
        return phase_bfly(f, budget);
    case FC_FFT_PHASE_POWER:
        return fc_fft_phase_power(f, budget);
    case FC_FFT_PHASE_SCAN:
        return fc_fft_phase_scan(f, budget);
    case FC_FFT_PHASE_WIDTH:
        return fc_fft_phase_width(f, budget);
    default:
        fc_fft_finish_frame(f);
        f->frame_samples = f->pushed - f->frame_begun_at;
        f->frames_done++;
        f->axis = (uint8_t)((f->axis + 1u) % FC_FFT_AXES);
        f->phase = FC_FFT_PHASE_IDLE;
        return 1;
    }
}

void fc_fft_step(fc_fft_t *f)
{
    if (!f->active) {
        return;
    }
    unsigned used = 0;
    /* A phase that ends mid-budget hands the rest to the next; FINISH ends the call, so
     * a frame's closing work never shares a step with a full budget of butterflies. */
    while (used < FC_FFT_STEP_UNITS) {
        if (f->phase == FC_FFT_PHASE_IDLE && !frame_begin(f)) {
            break;
        }
        const bool closing = f->phase == FC_FFT_PHASE_FINISH;
        used += run_phase(f, FC_FFT_STEP_UNITS - used);
        if (closing) {
            break;
        }
    }
    f->last_units = used;
    if (used > f->max_units) {
        f->max_units = used;
    }
}
