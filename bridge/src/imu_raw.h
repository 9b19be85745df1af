/*
 * imu_raw.h - the IMU chip's own samples at its output data rate (ODR), for the log.
 *
 * The flight controller reads the chip once per physics step, and the stage computes
 * only that read (sensor_stage.c chip_read: the rigid-body ramp folded into one linear
 * map, each vibration line through the AAF's gain at its frequency). To look at the
 * vibration above the FC's Nyquist frequency, where the FC sees only its alias, a run
 * may ask for the samples the chip's output register holds at every ODR tick: this
 * block produces them, per physics step, into rows the caller owns.
 *
 * Each tick j = 1..n of a step (n = ODR x dt): the rigid-body signal at the IMU,
 * linear from the step before to this one, through the same AAF sample by sample
 * (from the chip's state at the step's start), plus every vibration line at that
 * tick's rotor phase (phase + omega dt j/n) with the gains of the FC's read. It works
 * on copies: the chip and the vibration model the FC's read uses are never written, so
 * logging raw samples cannot change a single FC sample.
 *
 * Why the lines cost little per tick: the rotor speed is held over a step, so a line's
 * value at any tick is Re(P z^j), P its complex amplitude at the step's start and z its
 * turn per tick, exp(j k omega dt / n). P comes from the FC read's own code
 * (sb_vib_step) on a copy with only that line left on, read at the start phase and a
 * quarter of the line's period later (the line is linear in its phasor, so the two reads
 * are Re P and -Im P). Two evaluations per line and step instead of one per line and
 * tick: the cost no longer grows with the ODR.
 *
 * Prop wash (vibration.h, when on) is a physics-rate signal, not a line: the copy with
 * every line off, stepped over the step, gives this step's value (its generator and
 * filters are the stage's, so the same draws); the rows take it linearly from the step
 * before to this one, so the last tick is again the FC's read.
 *
 * Not in the rows: the per-read bias, white noise and temperature drift (drawn once per
 * FC sample, so a chip-rate version of them would be invented). The mounting rotation and
 * the full-scale clipping are applied, as the register holds them.
 *
 * Pure C: no heap, no globals, no OS.
 */
#ifndef SB_IMU_RAW_H
#define SB_IMU_RAW_H

#include <stddef.h>
#include <stdint.h>

#include "imu_chip.h"
#include "vibration.h"

/* One chip sample, as tools/logs/imu_raw_log.py RAW_DTYPE reads it (32 bytes). */
typedef struct {
    int64_t sim_ns;               /* the ODR tick [ns of sim time] */
    float accel_frd_m_s2[3];      /* IMU axes (the misaligned mounting's) */
    float gyro_frd_rad_s[3];
} sb_imu_raw_row;

_Static_assert(sizeof(sb_imu_raw_row) == 32, "sb_imu_raw_row is the log's 32-byte row");

/* One vibration line over a step: value at tick j = Re((re + j im) (zc + j zs)^j). */
typedef struct {
    double re[6], im[6];          /* its accel xyz, gyro xyz phasor at the step's start */
    double zc, zs;                /* its turn per ODR tick */
} sb_imu_raw_line;

#define SB_IMU_RAW_LINES (4 * (1 + SB_VIB_RIPPLES))   /* imbalance + ripples, per rotor */

typedef struct {
    sb_imu_raw_row *rows;         /* the caller's rows; NULL: raw logging off */
    size_t cap;                   /* rows it holds */
    size_t n_rows;                /* rows written since the caller last took them */
    uint64_t dropped;             /* samples lost to a full buffer (caller took too late) */
    int n;                        /* ODR ticks per physics step */
    int64_t dt_ns;                /* physics step [ns] (the rows' times) */
    double dt_s;                  /* the same in s, the stage's own (the lines' phases) */
    const double *rot;            /* R_imu_from_body, row-major, or NULL */
    double range_accel, range_gyro;   /* full scale [m/s^2], [rad/s] */
    sb_imu_chip chip;             /* scratch: the stage's chip, advanced tick by tick */
    sb_vibration vib;             /* scratch: the stage's vibration, one line on at a time */
    sb_imu_raw_line lines[SB_IMU_RAW_LINES];   /* this step's lines */
    double wash[6], wash_prev[6]; /* prop wash of this step and the one before */
    int wash_primed;              /* wash_prev holds a step */
} sb_imu_raw;

/* Start writing into rows[cap] (NULL: stop). n ticks per step of dt_ns (= dt_s); rot as
 * above. */
void sb_imu_raw_bind(sb_imu_raw *r, sb_imu_raw_row *rows, size_t cap, int n, int64_t dt_ns,
                     double dt_s, const double *rot, double range_accel, double range_gyro);

/* The step ending at end_ns: n rows from the chip and vibration as they stand at the
 * step's START (before the stage advances them), the rigid-body signal prev6 -> cur6
 * (accel xyz, gyro xyz), rotor speeds omega held over the step. Rows that do not fit
 * are counted in dropped. */
void sb_imu_raw_step(sb_imu_raw *r, const sb_imu_chip *chip, const sb_vibration *vib,
                     const double prev6[6], const double cur6[6], const double omega[4],
                     int64_t end_ns);

/* The rows written since the last call; the next step writes from the first row again. */
size_t sb_imu_raw_take(sb_imu_raw *r);

#endif /* SB_IMU_RAW_H */
