/*
 * lowrate.c - a low-rate sensor's schedule and noise rows (lowrate.h).
 */
#include "lowrate.h"

#include "step_maths.h"

int sb_lowrate_start(sb_lowrate *lr, double rate_hz)
{
    if (!(rate_hz > 0.0))
        return -1;
    lr->rate_hz = rate_hz;
    lr->m = 1;
    lr->next_ns = sb_due_ns(1, rate_hz);
    lr->on = 1;
    return 0;
}

void sb_lowrate_set_noise(sb_lowrate *lr, const double *noise, size_t rows, size_t pos)
{
    lr->noise = noise;
    lr->rows = rows;
    lr->pos = pos;
}

const double *sb_lowrate_take(sb_lowrate *lr, size_t width)
{
    if (sb_lowrate_spent(lr))
        return NULL;
    lr->next_ns = sb_due_ns(++lr->m, lr->rate_hz);
    return lr->noise + width * lr->pos++;
}
