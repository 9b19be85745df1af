/*
 * fc_fft.h - in-flight gyro FFT, compatible with ArduCopter 4.6's FFT_* parameters
 * (AP_GyroFFT with AP_HAL::DSP), feeding the harmonic notch's MODE 4.
 *
 * What it does, per axis in turn (roll, pitch, yaw, as ArduPilot's round robin):
 * a Hann-windowed radix-2 FFT of the last FFT_WINDOW_SIZE gyro samples every
 * (1 - FFT_WINDOW_OLAP) windows, the power spectrum (optionally averaged over
 * FFT_NUM_FRAMES frames), the three strongest peaks in FFT_MINHZ..FFT_MAXHZ with
 * sub-bin interpolation (Quinn's second estimator on the complex bins, Jain's on
 * averaged power), their SNR against a noise reference learned while the vehicle is
 * still (FFT_SNR_REF), their -FFT_ATT_REF dB bandwidth, peak tracking across frames,
 * the harmonic fit of the strongest peak to a lower one (FFT_HMNC_FIT) and hover
 * learning of FFT_FREQ_HOVER / FFT_BW_HOVER / FFT_THR_REF.
 *
 * Why the work is spread: ArduPilot runs the FFT in its own thread; a bare-metal
 * core has none, so fc_fft_step does at most FC_FFT_STEP_UNITS units of work per IMU
 * sample (a unit: one windowed sample, one butterfly, one bin's power, one bin
 * scanned) and no IMU step pays for a whole FFT.
 *
 * Gyro samples enter in rad/s and are kept in ArduPilot's window units (int16 counts of
 * a +-2000 deg/s gyro, _gyro_raw_sampling_multiplier), so FFT_SNR_REF, FFT_ATT_REF and
 * the energies in FTN2 mean what they mean in an ArduCopter log.
 *
 * Where it differs from AP_GyroFFT, and why: health (FH) counts the roll and pitch axes
 * only (the frequency never uses yaw, whose quiet frames made ArduPilot's flicker);
 * frequencies stay float (DSP::calc_frequency truncates to whole Hz); energy and bandwidth
 * are low-passed without the median ArduPilot 4.6 puts before them; with FFT_NUM_FRAMES the
 * average is per axis (ArduPilot's sliding window is shared by the round-robin axes); no
 * self-test of every bin before the calibration text (the transform is the one
 * tests/fc_sil/test_fft.py checks against numpy). Pure C, float32, no heap, no globals;
 * buffers are sized for FC_FFT_MAX_WINDOW (a board with less RAM builds with
 * -DFC_FFT_MAX_WINDOW=256, as ArduPilot caps non-H7 boards).
 */
#ifndef FC_FFT_H
#define FC_FFT_H

#include <stdbool.h>
#include <stdint.h>

#include "fc_status.h"

#ifndef FC_FFT_MAX_WINDOW
#define FC_FFT_MAX_WINDOW 512   /* largest FFT_WINDOW_SIZE kept (SITL/H7 cap) */
#endif
#define FC_FFT_MIN_WINDOW 32
#define FC_FFT_MAX_BINS (FC_FFT_MAX_WINDOW / 2 + 1)   /* DC .. Nyquist */
#define FC_FFT_RING (2 * FC_FFT_MAX_WINDOW)          /* a window and up to a window of hop */
#define FC_FFT_MAX_PEAKS 3      /* FrequencyPeak::MAX_TRACKED_PEAKS */
#define FC_FFT_MAX_FRAMES 8     /* FFT_NUM_FRAMES top (DSP::MAX_SLIDING_WINDOW_SIZE) */
#define FC_FFT_AXES 3
/* The declared share of one IMU step: at most this many work units per fc_fft_step,
 * plus a fixed handful of operations to close a frame (tests/fc_sil/test_fft_work.py). */
#define FC_FFT_STEP_UNITS 64

/* FFT_OPTIONS bits (ArduCopter 4.6) */
#define FC_FFT_OPT_POST_FILTER 0x1u  /* analyse the gyro after the notches and low-pass */
#define FC_FFT_OPT_ESC_CHECK 0x2u    /* warn of noise at an ESC-reported motor frequency
                                        * (with bit 0 and no FFT-driven notch; fc_fft_esc.c) */

/* Peak slots, ArduPilot's FrequencyPeak: the strongest, the second, the third. */
enum { FC_FFT_CENTER = 0, FC_FFT_LOWER = 1, FC_FFT_UPPER = 2 };

typedef struct fc_fft_config {
    bool enable;              /* FFT_ENABLE */
    float min_hz;             /* FFT_MINHZ: lower edge of the search [Hz] */
    float max_hz;             /* FFT_MAXHZ: upper edge, capped at 0.48 of the sample rate [Hz] */
    uint8_t sample_mode;      /* FFT_SAMPLE_MODE: 0 every gyro sample, k: loop rate / k */
    uint16_t window_size;     /* FFT_WINDOW_SIZE: rounded to a power of 2 in 32..MAX */
    float window_overlap;     /* FFT_WINDOW_OLAP: 0..0.9 */
    float freq_hover_hz;      /* FFT_FREQ_HOVER: learned hover frequency, start value [Hz] */
    float thr_ref;            /* FFT_THR_REF: learned throttle reference, start value */
    float snr_ref_db;         /* FFT_SNR_REF: a peak needs this SNR to count [dB] */
    float att_ref_db;         /* FFT_ATT_REF: bandwidth edges this far below the peak [dB] */
    float bw_hover_hz;        /* FFT_BW_HOVER: learned hover bandwidth, start value [Hz] */
    float hmnc_fit_pct;       /* FFT_HMNC_FIT: harmonic-fit threshold [%]; 0 = no matching */
    uint8_t hmnc_peak;        /* FFT_HMNC_PEAK: 0 auto, 1-3 a slot, 4 roll only, 5 pitch only */
    uint8_t num_frames;       /* FFT_NUM_FRAMES: 0 = no averaging, else 2..8 */
    uint8_t options;          /* FFT_OPTIONS bits (FC_FFT_OPT_*) */
    uint16_t harmonics;       /* the FFT-driven notch's INS_HNTCH_HMNCS; 0 = none (-> 3) */
    uint8_t notches;          /* dynamic notches per harmonic the notch runs (1 unless per-peak) */
} fc_fft_config_t;

/* The tracked state of one peak slot on one axis (FTN2), filtered across frames. */
typedef struct fc_fft_track {
    float freq_hz;            /* median-of-3 then low-pass [Hz] */
    float prev_freq_hz;       /* the value before the latest frame (slewed output) [Hz] */
    float bw_hz;              /* -FFT_ATT_REF dB width, low-passed [Hz] */
    float energy;             /* bin power x width x 5/6, low-passed [counts^2] */
    float median[3];          /* the last three raw frequencies [Hz] */
    uint8_t median_n;
    uint8_t missed;           /* frames without a valid peak in a row */
} fc_fft_track_t;

/* One frame's raw findings for one peak (DSP FrequencyPeakData). */
typedef struct fc_fft_found {
    uint16_t bin;             /* 0 = none */
    float power;              /* its bin's power [counts^2] */
    float freq_hz;            /* interpolated [Hz] */
    float width_hz;           /* -FFT_ATT_REF dB width [Hz] */
} fc_fft_found_t;

/* FFT_OPTIONS bit 1, ArduCopter's motor-noise check (AP_Vehicle::check_motor_noise): the
 * SNR the post-filter FFT sees at each ESC-reported motor frequency, low-passed per motor. */
#define FC_FFT_ESC_MAX 8          /* motors checked (the core's FC_ESC_MAX) */
typedef struct fc_fft_esc_noise {
    float energy_db[FC_FFT_ESC_MAX]; /* low-passed SNR at each motor's frequency [dB] */
    bool seen[FC_FFT_ESC_MAX];       /* the motor's filter holds a value (the first sets it) */
    float since_warning_s;           /* since the last warning, or since init [s] */
} fc_fft_esc_noise_t;

/* What ArduCopter's "FFT: calibrated %.1fKHz/%.1fHz/%.1fHz" reports (AP_GyroFFT::pre_arm_check). */
typedef struct fc_fft_calibration {
    float sample_khz;         /* FFT sample rate, whole Hz as ArduPilot keeps it, in kHz */
    float half_bin_hz;        /* half a bin: the worst frequency error of the search [Hz] */
    float output_hz;          /* frames per second over the three axes [Hz] */
} fc_fft_calibration_t;

typedef struct fc_fft {
    fc_fft_config_t cfg;
    bool active;              /* enabled and configured with a usable sample rate */
    /* derived from the configuration */
    uint16_t n;               /* window size */
    uint8_t log2n;
    uint16_t hop;             /* samples per frame (per axis) */
    uint16_t decim;           /* gyro samples averaged per FFT sample */
    uint16_t start_bin, end_bin;
    float fs_hz;              /* FFT sample rate [Hz] */
    float bin_hz;             /* bin width [Hz] */
    float att_cutoff;         /* 10^(-FFT_ATT_REF/10) */
    float harmonic_mult;      /* second tracked harmonic / first */
    uint8_t tracked_peaks;    /* 1..FC_FFT_MAX_PEAKS */
    float alpha_freq, alpha_energy, alpha_fit; /* per-frame low-pass factors */
    float window_scale;       /* 2 / (sum of the Hann window)^2 */
    float hann[FC_FFT_MAX_WINDOW];
    float cos_t[FC_FFT_MAX_WINDOW / 2], sin_t[FC_FFT_MAX_WINDOW / 2];
    uint16_t bitrev[FC_FFT_MAX_WINDOW];
    /* input: the gyro history per axis, in window units */
    float ring[FC_FFT_AXES][FC_FFT_RING];
    uint32_t pushed;          /* FFT samples pushed (free-running) */
    uint32_t next_start[FC_FFT_AXES]; /* first sample of each axis' next window */
    float decim_sum[FC_FFT_AXES];
    uint16_t decim_count;
    /* the frame in progress */
    uint8_t phase;            /* see fc_fft.c */
    uint8_t axis;
    uint32_t cursor;          /* progress within the phase */
    uint32_t frame_start;
    uint32_t frame_begun_at;  /* `pushed` when the frame began (FTN1 Tc) */
    float re[FC_FFT_MAX_WINDOW], im[FC_FFT_MAX_WINDOW];
    float power[FC_FFT_MAX_BINS];
    fc_fft_found_t found[FC_FFT_MAX_PEAKS];
    uint8_t found_n;
    uint16_t walk;            /* bandwidth walk offset within the WIDTH phase */
    /* averaging (FFT_NUM_FRAMES) and the noise reference */
    float frames[FC_FFT_AXES][FC_FFT_MAX_FRAMES][FC_FFT_MAX_BINS];
    float avg[FC_FFT_AXES][FC_FFT_MAX_BINS];
    uint8_t frame_slot[FC_FFT_AXES];
    float ref_energy[FC_FFT_AXES][FC_FFT_MAX_BINS];
    uint16_t skip_frames;     /* frames to let pass before the reference is learned */
    uint16_t calib_frames[FC_FFT_AXES]; /* reference frames still to add per axis */
    uint8_t needs_calibration; /* bit per axis */
    /* results (FTN1 / FTN2) */
    fc_fft_track_t track[FC_FFT_AXES][FC_FFT_MAX_PEAKS];
    uint8_t tracked_slot[FC_FFT_AXES]; /* slot taken as the fundamental per axis */
    uint8_t distorted[FC_FFT_AXES];    /* slot swaps still allowed (AP _distorted_cycles) */
    float harmonic_fit[FC_FFT_AXES];   /* filtered fit [%] (100 = none) */
    float snr_db[FC_FFT_AXES];         /* SNR of the strongest peak, latest frame [dB] */
    /* SNR of the latest frame's peaks, strongest first, as slots (AP update_snr_values) [dB] */
    float slot_snr_db[FC_FFT_AXES][FC_FFT_MAX_PEAKS];
    uint8_t peaks[FC_FFT_AXES];        /* peaks (valid or held) in each axis' latest frame */
    uint32_t good_at[FC_FFT_AXES];     /* `pushed` at the last frame with a peak, +1 (0 never) */
    uint32_t output_at[FC_FFT_AXES];   /* `pushed` at each axis' latest output */
    uint32_t frame_samples;   /* FFT samples the latest frame took to compute (Tc) */
    uint32_t frames_done;
    /* hover learning (FFT_FREQ_HOVER, FFT_BW_HOVER, FFT_THR_REF), saved on disarm */
    float freq_hover_hz, bw_hover_hz, thr_ref;
    bool learned;             /* hover values moved since the last save */
    fc_fft_esc_noise_t esc_noise;      /* FFT_OPTIONS bit 1's state (fc_fft_esc.c) */
    /* the work-spread account (tests, bench) */
    uint32_t last_units;      /* units done by the latest fc_fft_step */
    uint32_t max_units;       /* the most in one call since init */
} fc_fft_t;

/* FTN1, ArduPilot's fields (AP_GyroFFT::write_log_messages). */
typedef struct fc_fft_ftn1 {
    float pk_avg_hz;          /* PkAvg: energy-weighted roll/pitch tracked frequency [Hz] */
    float bw_avg_hz;          /* BwAvg: its bandwidth [Hz] */
    float snr_db[3];          /* SnX, SnY, SnZ [dB] */
    float fit_pct[3];         /* FtX, FtY, FtZ: harmonic fit [%] */
    uint8_t health;           /* FH */
    uint32_t cycle_us;        /* Tc: sim time the latest frame took (no wall clock here) [us] */
} fc_fft_ftn1_t;

/* Set up (all state cleared). sample_hz: the gyro rate; loop_hz: the rate loop's rate
 * (FFT_SAMPLE_MODE > 0 samples at loop_hz / mode). */
void fc_fft_init(fc_fft_t *f, const fc_fft_config_t *cfg, float sample_hz, float loop_hz);
/* New configuration or rates: the engine restarts (and recalibrates) only when the
 * window, overlap, sample rate or averaging changed; otherwise the tracks are kept. */
void fc_fft_configure(fc_fft_t *f, const fc_fft_config_t *cfg, float sample_hz, float loop_hz);
/* One gyro sample (FRD, rad/s). Cheap: a ring write. Non-finite samples are skipped. */
void fc_fft_push(fc_fft_t *f, const float gyro_frd_rad_s[3]);
/* A share of the analysis (at most FC_FFT_STEP_UNITS units). Call once per IMU sample. */
void fc_fft_step(fc_fft_t *f);

/* The notch's MODE 4 inputs (AP_GyroFFT::get_weighted_noise_center_freq_hz): the tracked
 * fundamental [Hz]. Off: FFT_MINHZ. No healthy peak: the throttle estimate
 * FFT_MINHZ * max(1, sqrt(throttle_out / FFT_THR_REF)) within FFT_MINHZ..FFT_MAXHZ. */
float fc_fft_center_freq_hz(const fc_fft_t *f, float throttle_out);
/* Per-peak notches (get_weighted_noise_center_frequencies_hz): up to max_n frequencies,
 * slot by slot; returns how many (>= 1), with the same fallbacks. */
unsigned fc_fft_center_freqs_hz(const fc_fft_t *f, float throttle_out, float *freqs_hz,
                                unsigned max_n);
/* What the notch's MODE 4 reads (agreed with fc_notch_feed.c): freqs_hz[0] the tracked
 * fundamental (fc_fft_center_freq_hz), freqs_hz[1..] the other tracked peaks in slot order
 * (per-peak notches, INS_HNTCH_OPTS bit 1): ArduPilot's set of frequencies, fundamental
 * first. Returns how many (>= 1). */
unsigned fc_fft_notch_freqs(const fc_fft_t *f, float throttle_out,
                            float freqs_hz[FC_FFT_MAX_PEAKS]);
/* Hover learning, ArduPilot's update_freq_hover: call while in a level, steady hover. */
void fc_fft_update_freq_hover(fc_fft_t *f, float dt_s, float throttle_out);
/* FTN1 and FTN2 (peak slot `slot`: PkX..Z, BwX..Z, EnX..Z as arrays [axis]). */
void fc_fft_ftn1(const fc_fft_t *f, float throttle_out, fc_fft_ftn1_t *out);
void fc_fft_ftn2(const fc_fft_t *f, unsigned slot, float pk_hz[3], float bw_hz[3],
                 float energy[3]);
/* The three figures of ArduCopter's calibration text, as it computes them. */
void fc_fft_calibration(const fc_fft_t *f, fc_fft_calibration_t *out);

/* AP_GyroFFT::has_noise_at_frequency_hz: the highest SNR [dB] of a tracked peak within one
 * bin of hz on a healthy axis; 0 when none (or the FFT is off). */
float fc_fft_noise_at_hz(const fc_fft_t *f, float hz);
/* FFT_OPTIONS bit 1: one check, to be called every FC_FFT_ESC_CHECK_S (ArduCopter's 5 Hz
 * task). motor_hz[i]: motor i's ESC-reported frequency [Hz], 0 for none or stale.
 * Checks only while armed, with FFT_OPTIONS bits 0 and 1, and with no notch following the
 * FFT (fft_notch false). Returns the motors to warn about now (bit i: motor i), their
 * energies in f->esc_noise.energy_db. */
#define FC_FFT_ESC_CHECK_S 0.2f
unsigned fc_fft_esc_noise_check(fc_fft_t *f, const float *motor_hz, unsigned n, bool armed,
                                bool fft_notch, float dt_s);

#endif /* FC_FFT_H */
