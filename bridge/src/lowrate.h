/*
 * lowrate.h - the schedule and noise rows of a sensor sampled below the physics rate (the
 * baro and mag at 100 Hz, the GNSS at its epochs): sample m is due at round(m * 1e9 /
 * rate_hz), each sample reads the next row of the caller's (rows, width) standard normals,
 * as bridge/lowrate.py's models do. One schedule for all three, so a sample advances the
 * same way whichever sensor it is.
 */
#ifndef SB_LOWRATE_H
#define SB_LOWRATE_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
    int on;                   /* configured (sb_lowrate_start) */
    double rate_hz;
    int64_t m, next_ns;       /* sample m is due at next_ns = round(m * 1e9 / rate_hz) */
    const double *noise;      /* (rows, width) standard normals, the caller's memory */
    size_t rows, pos;
    uint32_t seq;             /* the next record's sequence number */
} sb_lowrate;

/* Start the schedule at sample 1; -1 unless rate_hz > 0. */
int sb_lowrate_start(sb_lowrate *lr, double rate_hz);

/* The next noise rows, read from row pos on. */
void sb_lowrate_set_noise(sb_lowrate *lr, const double *noise, size_t rows, size_t pos);

/* Sample m due: its noise row (width doubles), the schedule moved to sample m + 1; NULL,
 * with nothing moved, when no row is left. */
const double *sb_lowrate_take(sb_lowrate *lr, size_t width);

/* 1 when the block's rows are used up (give the next before the next sample). */
static inline int sb_lowrate_spent(const sb_lowrate *lr)
{
    return lr->pos >= lr->rows;
}

#endif /* SB_LOWRATE_H */
