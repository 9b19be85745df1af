/*
 * imu_chip.h - the signal path inside an ICM-42688-class IMU chip: samples at the
 * chip's output data rate (ODR), its anti-alias filter (AAF), then the flight
 * controller reads every n-th sample (decimation, no further filter: what reaches the
 * register is what the FC gets). Vibration above the FC's Nyquist frequency that the
 * AAF lets through folds down, as on a real chip with the AAF off or the ODR low.
 *
 * The AAF: the ICM-42688-P datasheet (DS-000347 v1.7, section 5.2) programs a 2nd-order
 * low-pass by its 3 dB bandwidth (AAF_DELT/DELTSQR/BITSHIFT, 42..3979 Hz) and does not
 * publish the pole placement; we take the maximally flat one (Butterworth, Q = 1/sqrt 2),
 * bilinear with the cutoff pre-warped so the 3 dB point is the declared one at the ODR.
 * bridge/vibration_consts.py aaf_gain gives the same filter's gain to Python.
 *
 * Pure C: no heap, no globals, no OS.
 */
#ifndef SB_IMU_CHIP_H
#define SB_IMU_CHIP_H

/* Constants of one run. */
typedef struct {
    double odr_hz;      /* the chip's data rate [Hz]; a whole multiple of the FC's rate */
    double aaf_hz;      /* AAF 3 dB bandwidth [Hz] */
    double aaf_order;   /* 0: AAF off; 2: on */
} sb_chip_consts;

/* Six channels (accel xyz, gyro xyz) through one biquad each, transposed direct form II. */
typedef struct {
    int on;                         /* AAF on */
    double odr_hz;                  /* the chip's data rate [Hz] */
    double b0, b1, b2, a1, a2;      /* y = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) x */
    double s1[6], s2[6];            /* filter state per channel */
    /* One physics step of n samples of a ramp from prev to cur, as a linear map of
     * (s1, s2, prev, cur) to (s1, s2, last output): rows s1, s2, y (sb_chip_ramp). */
    int ramp_n;
    double ramp[3][4];
} sb_imu_chip;

/* A defined chip: the AAF's coefficients for these constants, state at zero. */
void sb_chip_init(sb_imu_chip *ch, const sb_chip_consts *c);

/* The filter at rest on a constant x (no start-up transient). */
void sb_chip_settle(sb_imu_chip *ch, const double x[6]);

/* One sample at the ODR: x in, the AAF's output in y (x copied when the AAF is off). */
void sb_chip_sample(sb_imu_chip *ch, const double x[6], double y[6]);

/* Prepare sb_chip_ramp for n samples per physics step (n >= 1). */
void sb_chip_ramp_init(sb_imu_chip *ch, int n);

/* The n samples (j = 1..n) of prev + j/n (cur - prev) through the filter, in O(1): the
 * state advances as n sb_chip_sample calls would move it; y is the last output. */
void sb_chip_ramp(sb_imu_chip *ch, const double prev[6], const double cur[6], double y[6]);

/* The AAF's complex gain at w_rad_s, as the filter runs at the ODR (1 when off): what
 * the chip does to a steady line of that frequency, aliases included (the discrete
 * filter's response is periodic in the ODR). */
void sb_chip_gain(const sb_imu_chip *ch, double w_rad_s, double *re, double *im);

/* The same from z^-1 = exp(-j w / odr) = zc + j zs, for callers that hold it already. */
void sb_chip_gain_z(const sb_imu_chip *ch, double zc, double zs, double *re, double *im);

#endif /* SB_IMU_CHIP_H */
