/*
 * imu_raw.c - see imu_raw.h.
 */
#include "imu_raw.h"

#include <math.h>
#include <string.h>

void sb_imu_raw_bind(sb_imu_raw *r, sb_imu_raw_row *rows, size_t cap, int n, int64_t dt_ns,
                     double dt_s, const double *rot, double range_accel, double range_gyro)
{
    r->rows = rows;
    r->cap = rows != NULL ? cap : 0;
    r->n_rows = 0;
    r->dropped = 0;
    r->n = n >= 1 ? n : 1;
    r->dt_ns = dt_ns;
    r->dt_s = dt_s;
    r->rot = rot;
    r->range_accel = range_accel;
    r->range_gyro = range_gyro;
    r->wash_primed = 0;
}

static double clamp(double x, double range)
{
    return x > range ? range : (x < -range ? -range : x);
}

/* v = R v for the accel and the gyro halves of y (the chip's axes are the mount's). */
static void rotate6(const double *m, double y[6])
{
    for (int h = 0; h < 6; h += 3) {
        const double x0 = y[h], x1 = y[h + 1], x2 = y[h + 2];
        y[h] = m[0] * x0 + m[1] * x1 + m[2] * x2;
        y[h + 1] = m[3] * x0 + m[4] * x1 + m[5] * x2;
        y[h + 2] = m[6] * x0 + m[7] * x1 + m[8] * x2;
    }
}

static void put_row(sb_imu_raw *r, const double y[6], int64_t t_ns)
{
    if (r->n_rows >= r->cap) {   /* never overwrite: a gap is counted, not hidden */
        r->dropped++;
        return;
    }
    sb_imu_raw_row *row = &r->rows[r->n_rows++];
    row->sim_ns = t_ns;
    for (int i = 0; i < 3; i++) {
        row->accel_frd_m_s2[i] = (float)clamp(y[i], r->range_accel);
        row->gyro_frd_rad_s[i] = (float)clamp(y[i + 3], r->range_gyro);
    }
}

#define HALF_PI 1.57079632679489661923

/* The line left on in r->vib (rotor i at speed w, order k) read at phase psi, into out:
 * sb_vib_step over no time, the other rotors stopped so only rotor i speaks. */
static void read_line(sb_imu_raw *r, const sb_imu_chip *chip, int i, double w, double psi,
                      double out[6])
{
    double omega[4] = {0.0, 0.0, 0.0, 0.0};
    omega[i] = w;
    r->vib.phase_rad[i] = psi;
    memset(out, 0, 6 * sizeof *out);
    sb_vib_step(&r->vib, omega, 0.0, chip, out);
}

/* Line l: its phasor at the step's start phase psi0 and its turn per tick (imu_raw.h). */
static void take_line(sb_imu_raw *r, const sb_imu_chip *chip, int i, double w, double k,
                      double psi0, sb_imu_raw_line *l)
{
    double in_phase[6], quadrature[6];
    read_line(r, chip, i, w, psi0, in_phase);
    read_line(r, chip, i, w, psi0 + HALF_PI / k, quadrature);
    for (int a = 0; a < 6; a++) {   /* Re(P e^{j pi/2}) = -Im P */
        l->re[a] = in_phase[a];
        l->im[a] = -quadrature[a];
    }
    const double th = k * w * r->dt_s / r->n;
    l->zc = cos(th);
    l->zs = sin(th);
}

/* This step's lines from the stage's vibration, one at a time; returns how many. The
 * scratch starts with every line off, each is switched on, read and off again. */
static int take_lines(sb_imu_raw *r, const sb_imu_chip *chip, const sb_vibration *vib,
                      const double omega[4])
{
    const sb_vib_consts *c = &vib->c;
    r->vib = *vib;
    memset(r->vib.c.imbalance_kg_m, 0, sizeof r->vib.c.imbalance_kg_m);
    memset(r->vib.c.ripple_frac, 0, sizeof r->vib.c.ripple_frac);
    int n = 0;
    for (int i = 0; i < 4; i++) {
        const double w = omega[i], psi0 = vib->phase_rad[i];
        if (!(w > 0.0))
            continue;   /* sb_vib_step: a stopped rotor forces nothing */
        if (c->imbalance_kg_m[i] > 0.0) {
            r->vib.c.imbalance_kg_m[i] = c->imbalance_kg_m[i];
            take_line(r, chip, i, w, 1.0, psi0, &r->lines[n++]);
            r->vib.c.imbalance_kg_m[i] = 0.0;
        }
        for (int h = 0; h < SB_VIB_RIPPLES; h++) {
            if (!(c->ripple_order[h] > 0.0) || !(c->ripple_frac[h] > 0.0))
                continue;
            r->vib.c.ripple_frac[h] = c->ripple_frac[h];
            take_line(r, chip, i, w, c->ripple_order[h], psi0, &r->lines[n++]);
            r->vib.c.ripple_frac[h] = 0.0;
        }
    }
    return n;
}

/* This step's prop wash into r->wash (0 when off), after take_lines left every line off
 * in the scratch; the step before's into r->wash_prev. */
static void take_wash(sb_imu_raw *r, const sb_imu_chip *chip, const double omega[4])
{
    memcpy(r->wash_prev, r->wash, sizeof r->wash);
    memset(r->wash, 0, sizeof r->wash);
    if (r->vib.c.wash_frac > 0.0)
        sb_vib_step(&r->vib, omega, r->dt_s, chip, r->wash);
    if (!r->wash_primed) {   /* no step before this one: hold the first */
        memcpy(r->wash_prev, r->wash, sizeof r->wash);
        r->wash_primed = 1;
    }
}

void sb_imu_raw_step(sb_imu_raw *r, const sb_imu_chip *chip, const sb_vibration *vib,
                     const double prev6[6], const double cur6[6], const double omega[4],
                     int64_t end_ns)
{
    /* Copies, so the FC's read (which advances the originals after this call) sees
     * exactly what it saw without raw logging. */
    const int n_lines = take_lines(r, chip, vib, omega);
    take_wash(r, chip, omega);
    r->chip = *chip;
    const int n = r->n;
    const int64_t start_ns = end_ns - r->dt_ns;
    for (int j = 1; j <= n; j++) {
        double x[6], y[6];
        /* the ramp's j-th input, the same expression sb_chip_ramp_init folds */
        const double f = (double)j / n;
        for (int i = 0; i < 6; i++)
            x[i] = prev6[i] + f * (cur6[i] - prev6[i]);
        sb_chip_sample(&r->chip, x, y);
        for (int a = 0; a < 6; a++)
            y[a] += r->wash_prev[a] + f * (r->wash[a] - r->wash_prev[a]);
        for (int l = 0; l < n_lines; l++) {   /* P z^j, one turn further each tick */
            sb_imu_raw_line *ln = &r->lines[l];
            for (int a = 0; a < 6; a++) {
                const double re = ln->re[a] * ln->zc - ln->im[a] * ln->zs;
                ln->im[a] = ln->re[a] * ln->zs + ln->im[a] * ln->zc;
                ln->re[a] = re;
                y[a] += re;
            }
        }
        if (r->rot != NULL)
            rotate6(r->rot, y);
        put_row(r, y, start_ns + (int64_t)j * r->dt_ns / n);
    }
}

size_t sb_imu_raw_take(sb_imu_raw *r)
{
    const size_t got = r->n_rows;
    r->n_rows = 0;
    return got;
}
