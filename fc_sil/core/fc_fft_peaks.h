/*
 * fc_fft_peaks.h - the in-flight FFT's frame phases after the transform, shared by
 * fc_fft.c (the pipeline) and fc_fft_peaks.c (what they compute). Internal to the FFT.
 */
#ifndef FC_FFT_PEAKS_H
#define FC_FFT_PEAKS_H

#include "fc_fft.h"

/* The frame pipeline's phases, in order (fc_fft.c explains each). */
enum {
    FC_FFT_PHASE_IDLE = 0,
    FC_FFT_PHASE_LOAD,
    FC_FFT_PHASE_BFLY,
    FC_FFT_PHASE_POWER,
    FC_FFT_PHASE_SCAN,
    FC_FFT_PHASE_WIDTH,
    FC_FFT_PHASE_FINISH
};

/* Each spends at most `budget` units and returns how many it spent. */
unsigned fc_fft_phase_power(fc_fft_t *f, unsigned budget);
unsigned fc_fft_phase_scan(fc_fft_t *f, unsigned budget);
unsigned fc_fft_phase_width(fc_fft_t *f, unsigned budget);
/* A found peak of the frame in progress: its interpolated frequency [Hz], its SNR against
 * the noise reference [dB], its energy (power x width x 5/6) once its width is in Hz. */
float fc_fft_peak_freq_hz(const fc_fft_t *f, const fc_fft_found_t *pk);
float fc_fft_peak_snr_db(const fc_fft_t *f, const fc_fft_found_t *pk);
float fc_fft_peak_energy(const fc_fft_t *f, const fc_fft_found_t *pk);
/* Interpolation, SNR, the noise reference's bookkeeping, tracking and harmonic fit. */
void fc_fft_finish_frame(fc_fft_t *f);

#endif /* FC_FFT_PEAKS_H */
