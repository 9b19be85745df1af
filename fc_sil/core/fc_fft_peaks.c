/*
 * fc_fft_peaks.c - from the transform to a frame's peaks (AP_HAL::DSP's
 * step_cmplx_mag, find_peaks, find_noise_width and calc_frequency, rewritten):
 * power per bin with averaging and the noise reference, the three strongest local
 * maxima, their -FFT_ATT_REF dB widths and their interpolated frequencies and SNR.
 */
#include "fc_fft_peaks.h"

#include "fc_math.h"

/* Quinn's tau (dspguru "how to interpolate the peak location of a DFT"). */
#define FC_FFT_SQRT_2_3 0.816496580927726f
#define FC_FFT_SQRT_6 2.449489742783178f
/* ArduPilot floors bin power at 1 count^2 before the SNR's logarithm. */
#define FC_FFT_POWER_FLOOR 1.0f

/* The spectrum the peaks are read from: averaged power with FFT_NUM_FRAMES, else the
 * latest frame's. */
static const float *spectrum(const fc_fft_t *f)
{
    return f->cfg.num_frames > 0 ? f->avg[f->axis] : f->power;
}

static bool calibrating_now(const fc_fft_t *f)
{
    const uint8_t a = f->axis;
    return ((f->needs_calibration >> a) & 1u) && f->skip_frames == 0 && f->calib_frames[a] > 0;
}

unsigned fc_fft_phase_power(fc_fft_t *f, unsigned budget)
{
    const uint8_t a = f->axis;
    const uint32_t last = f->n / 2u;
    const uint8_t frames = f->cfg.num_frames;
    const bool calib = calibrating_now(f);
    unsigned done = 0;
    while (done < budget && f->cursor <= last) {
        const uint32_t k = f->cursor++;
        const float p = (f->re[k] * f->re[k] + f->im[k] * f->im[k]) * f->window_scale;
        f->power[k] = p;
        float used = p;
        if (frames > 0) {
            /* a sliding mean over the last FFT_NUM_FRAMES frames of this axis */
            float *slot = &f->frames[a][f->frame_slot[a]][k];
            const float share = p / (float)frames;
            f->avg[a][k] += share - *slot;
            *slot = share;
            used = f->avg[a][k];
        }
        if (calib && k >= 1u) {
            f->ref_energy[a][k] += used;
        }
        done++;
    }
    if (f->cursor > last) {
        if (frames > 0) {
            f->frame_slot[a] = (uint8_t)((f->frame_slot[a] + 1u) % frames);
        }
        f->phase = FC_FFT_PHASE_SCAN;
        f->cursor = f->start_bin;
        f->found_n = 0;
        for (int i = 0; i < FC_FFT_MAX_PEAKS; i++) {
            f->found[i] = (fc_fft_found_t){0};
        }
    }
    return done;
}

/* Keep the three strongest local maxima, strongest first. */
static void keep_peak(fc_fft_t *f, uint16_t bin, float power)
{
    int at = f->found_n < FC_FFT_MAX_PEAKS ? f->found_n : FC_FFT_MAX_PEAKS;
    if (at == FC_FFT_MAX_PEAKS && !(power > f->found[FC_FFT_MAX_PEAKS - 1].power)) {
        return;
    }
    if (at == FC_FFT_MAX_PEAKS) {
        at--;
    } else {
        f->found_n++;
    }
    while (at > 0 && power > f->found[at - 1].power) {
        f->found[at] = f->found[at - 1];
        at--;
    }
    f->found[at] = (fc_fft_found_t){.bin = bin, .power = power, .width_hz = 1.0f};
}

unsigned fc_fft_phase_scan(fc_fft_t *f, unsigned budget)
{
    const float *s = spectrum(f);
    /* one bin past FFT_MAXHZ so a peak on the edge is seen as a peak */
    const uint32_t top = f->end_bin + 1u < f->n / 2u ? f->end_bin + 1u : f->n / 2u - 1u;
    unsigned done = 0;
    while (done < budget && f->cursor <= top) {
        const uint32_t k = f->cursor++;
        if (s[k] >= s[k - 1u] && s[k] > s[k + 1u]) {
            keep_peak(f, (uint16_t)(k > f->end_bin ? f->end_bin : k), s[k]);
        }
        done++;
    }
    if (f->cursor > top) {
        f->phase = f->found_n > 0 ? FC_FFT_PHASE_WIDTH : FC_FFT_PHASE_FINISH;
        f->cursor = 0;
        f->walk = 1;
    }
    return done;
}

/* Walk from each peak up (even cursor) and down (odd) until the power falls below
 * peak x 10^(-FFT_ATT_REF/10); the edge is taken mid-bin. No edge within
 * FFT_MINHZ..FFT_MAXHZ adds nothing (DSP::find_noise_width). Width starts at one bin. */
unsigned fc_fft_phase_width(fc_fft_t *f, unsigned budget)
{
    const float *s = spectrum(f);
    unsigned done = 0;
    while (done < budget && f->cursor < 2u * f->found_n) {
        fc_fft_found_t *pk = &f->found[f->cursor >> 1];
        const bool up = (f->cursor & 1u) == 0;
        const int b = up ? pk->bin + f->walk : pk->bin - f->walk;
        bool edge_done = up ? b > f->end_bin : b < f->start_bin;
        if (!edge_done && s[b] < s[pk->bin] * f->att_cutoff) {
            pk->width_hz += (float)f->walk - 0.5f;
            edge_done = true;
        }
        if (edge_done) {
            f->cursor++;
            f->walk = 1;
        } else {
            f->walk++;
        }
        done++;
    }
    if (f->cursor >= 2u * f->found_n) {
        f->phase = FC_FFT_PHASE_FINISH;
    }
    return done;
}

static float quinn_tau(float x)
{
    const float p1 = logf(3.0f * x * x + 6.0f * x + 1.0f);
    const float p2 = logf((x + 1.0f - FC_FFT_SQRT_2_3) / (x + 1.0f + FC_FFT_SQRT_2_3));
    return 0.25f * p1 - (FC_FFT_SQRT_6 / 24.0f) * p2;
}

/* Quinn's second estimator on the complex bins around k: the offset in bins, -0.5..0.5. */
static float quinn_offset(const fc_fft_t *f, uint16_t k)
{
    const float d2 = f->re[k] * f->re[k] + f->im[k] * f->im[k];
    if (k <= 1u || k >= f->n / 2u || !(d2 > 0.0f)) {
        return 0.0f;
    }
    const float ap = (f->re[k + 1] * f->re[k] + f->im[k + 1] * f->im[k]) / d2;
    const float am = (f->re[k - 1] * f->re[k] + f->im[k - 1] * f->im[k]) / d2;
    if (fabsf(1.0f - ap) < 0.01f || fabsf(1.0f - am) < 0.01f) {
        return 0.0f;
    }
    const float dp = -ap / (1.0f - ap), dm = am / (1.0f - am);
    const float d = (dp + dm) * 0.5f + quinn_tau(dp * dp) - quinn_tau(dm * dm);
    return fc_finitef(d) ? fc_constrainf(d, -0.5f, 0.5f) : 0.0f;
}

/* Jain's estimator on (averaged) power, where no complex bins exist. */
static float jain_offset(const fc_fft_t *f, const float *s, uint16_t k)
{
    if (k <= 1u || k >= f->n / 2u) {
        return 0.0f;
    }
    float d;
    if (s[k - 1] > s[k + 1]) {
        const float a = s[k] / s[k - 1];
        d = a / (1.0f + a) - 1.0f;
    } else {
        const float a = s[k + 1] / s[k];
        d = a / (1.0f + a);
    }
    return fc_finitef(d) ? fc_constrainf(d, -0.5f, 0.5f) : 0.0f;
}

float fc_fft_peak_freq_hz(const fc_fft_t *f, const fc_fft_found_t *pk)
{
    const float *s = spectrum(f);
    if (pk->bin == 0 || !(s[pk->bin] > 0.0f)) {
        return (float)f->start_bin * f->bin_hz;
    }
    const uint16_t k = pk->bin < f->start_bin ? f->start_bin
                       : (pk->bin > f->end_bin ? f->end_bin : pk->bin);
    const float d = f->cfg.num_frames > 0 ? jain_offset(f, s, k) : quinn_offset(f, k);
    return ((float)k + d) * f->bin_hz;
}

float fc_fft_peak_snr_db(const fc_fft_t *f, const fc_fft_found_t *pk)
{
    const float *s = spectrum(f);
    const float scale = sqrtf((float)(2u * (f->n / f->hop))) / (float)(2u * (f->n / f->hop));
    const float e = fmaxf(FC_FFT_POWER_FLOOR, s[pk->bin]);
    const float ref = fmaxf(FC_FFT_POWER_FLOOR, f->ref_energy[f->axis][pk->bin] * scale);
    return 10.0f * (log10f(e) - log10f(ref));
}

float fc_fft_peak_energy(const fc_fft_t *f, const fc_fft_found_t *pk)
{
    /* the peak's energy is an integral; ArduPilot takes amplitude x width x 5/6 */
    return spectrum(f)[pk->bin] * pk->width_hz * 0.8333f;
}
