/*
 * imu_chip.c - see imu_chip.h.
 */
#include "imu_chip.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979311600

void sb_chip_init(sb_imu_chip *ch, const sb_chip_consts *c)
{
    memset(ch, 0, sizeof *ch);
    ch->odr_hz = c->odr_hz;
    ch->on = c->aaf_order > 0.0 && c->aaf_hz > 0.0 && c->aaf_hz < 0.5 * c->odr_hz;
    if (!ch->on)
        return;
    /* Bilinear 2nd-order Butterworth: K = tan(pi fc / fs) pre-warps the 3 dB point. */
    const double k = tan(PI * c->aaf_hz / c->odr_hz), q = 0.70710678118654752440;
    const double norm = 1.0 / (1.0 + k / q + k * k);
    ch->b0 = k * k * norm;
    ch->b1 = 2.0 * ch->b0;
    ch->b2 = ch->b0;
    ch->a1 = 2.0 * (k * k - 1.0) * norm;
    ch->a2 = (1.0 - k / q + k * k) * norm;
}

void sb_chip_settle(sb_imu_chip *ch, const double x[6])
{
    /* y = x in steady state: s2 = (b2 - a2) x, s1 = (b1 - a1) x + s2 */
    for (int i = 0; i < 6; i++) {
        ch->s2[i] = (ch->b2 - ch->a2) * x[i];
        ch->s1[i] = (ch->b1 - ch->a1) * x[i] + ch->s2[i];
    }
}

void sb_chip_sample(sb_imu_chip *ch, const double x[6], double y[6])
{
    if (!ch->on) {
        memcpy(y, x, 6 * sizeof *y);
        return;
    }
    for (int i = 0; i < 6; i++) {
        const double out = ch->b0 * x[i] + ch->s1[i];
        ch->s1[i] = ch->b1 * x[i] - ch->a1 * out + ch->s2[i];
        ch->s2[i] = ch->b2 * x[i] - ch->a2 * out;
        y[i] = out;
    }
}

void sb_chip_gain(const sb_imu_chip *ch, double w, double *re, double *im)
{
    const double th = ch->on ? w / ch->odr_hz : 0.0;
    sb_chip_gain_z(ch, cos(th), -sin(th), re, im);
}

void sb_chip_gain_z(const sb_imu_chip *ch, double c1, double s1, double *re, double *im)
{
    if (!ch->on) {
        *re = 1.0;
        *im = 0.0;
        return;
    }
    /* H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2), z^-1 = c1 + j s1 */
    const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * s1 * c1;
    const double nr = ch->b0 + ch->b1 * c1 + ch->b2 * c2, ni = ch->b1 * s1 + ch->b2 * s2;
    const double dr = 1.0 + ch->a1 * c1 + ch->a2 * c2, di = ch->a1 * s1 + ch->a2 * s2;
    const double g = 1.0 / (dr * dr + di * di);
    *re = (nr * dr + ni * di) * g;
    *im = (ni * dr - nr * di) * g;
}

/* One channel of the biquad, for the ramp map: state (s1, s2), input x, output returned. */
static double biquad1(const sb_imu_chip *ch, double st[2], double x)
{
    const double out = ch->b0 * x + st[0];
    st[0] = ch->b1 * x - ch->a1 * out + st[1];
    st[1] = ch->b2 * x - ch->a2 * out;
    return out;
}

void sb_chip_ramp_init(sb_imu_chip *ch, int n)
{
    ch->ramp_n = n;
    if (!ch->on)
        return;
    /* The map is linear: its columns are the responses to each basis input. */
    for (int col = 0; col < 4; col++) {
        double st[2] = {col == 0 ? 1.0 : 0.0, col == 1 ? 1.0 : 0.0};
        const double prev = col == 2 ? 1.0 : 0.0, cur = col == 3 ? 1.0 : 0.0;
        double y = 0.0;
        for (int j = 1; j <= n; j++)
            y = biquad1(ch, st, prev + (double)j / n * (cur - prev));
        ch->ramp[0][col] = st[0];
        ch->ramp[1][col] = st[1];
        ch->ramp[2][col] = y;
    }
}

void sb_chip_ramp(sb_imu_chip *ch, const double prev[6], const double cur[6], double y[6])
{
    if (!ch->on) {   /* the last sample of the ramp is cur */
        memcpy(y, cur, 6 * sizeof *y);
        return;
    }
    const double (*m)[4] = (const double (*)[4])ch->ramp;
    for (int i = 0; i < 6; i++) {
        const double a = ch->s1[i], b = ch->s2[i];
        y[i] = m[2][0] * a + m[2][1] * b + m[2][2] * prev[i] + m[2][3] * cur[i];
        ch->s1[i] = m[0][0] * a + m[0][1] * b + m[0][2] * prev[i] + m[0][3] * cur[i];
        ch->s2[i] = m[1][0] * a + m[1][1] * b + m[1][2] * prev[i] + m[1][3] * cur[i];
    }
}
