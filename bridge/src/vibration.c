/*
 * vibration.c - see vibration.h. Complex amplitudes are (re, im) pairs of doubles; a
 * real signal is Re(C exp(j k psi)).
 */
#include "vibration.h"

#include <math.h>
#include <string.h>

#define TWO_PI (2.0 * 3.14159265358979311600)

void sb_vib_second_order(double f_hz, double zeta, double w, double *re, double *im)
{
    if (!(f_hz > 0.0)) {
        *re = 1.0;
        *im = 0.0;
        return;
    }
    const double wn = TWO_PI * f_hz;
    /* wn^2 / (wn^2 - w^2 + j 2 zeta wn w) */
    const double dr = wn * wn - w * w, di = 2.0 * zeta * wn * w;
    const double g = wn * wn / (dr * dr + di * di);
    *re = g * dr;
    *im = -g * di;
}

/* The unit response of force phasor f at hub r: a = f / m, alpha = I^-1 (r x f), and the
 * acceleration at the IMU's place a + alpha x r_imu (complex: the cross products are
 * linear, so real and imaginary parts go through alike). */
static void unit_response(const sb_vib_consts *c, const double r[3], const double f_re[3],
                          const double f_im[3], sb_vib_unit *u)
{
    const double *f[2] = {f_re, f_im};
    double *al[2] = {u->al_re, u->al_im}, *p[2] = {u->p_re, u->p_im};
    const double *q = c->imu_lever_frd_m;
    for (int part = 0; part < 2; part++) {
        const double *fp = f[part];
        double *a = al[part], *pp = p[part];
        a[0] = (r[1] * fp[2] - r[2] * fp[1]) / c->inertia_kg_m2[0];
        a[1] = (r[2] * fp[0] - r[0] * fp[2]) / c->inertia_kg_m2[1];
        a[2] = (r[0] * fp[1] - r[1] * fp[0]) / c->inertia_kg_m2[2];
        pp[0] = fp[0] / c->mass_kg + (a[1] * q[2] - a[2] * q[1]);
        pp[1] = fp[1] / c->mass_kg + (a[2] * q[0] - a[0] * q[2]);
        pp[2] = fp[2] / c->mass_kg + (a[0] * q[1] - a[1] * q[0]);
    }
}

void sb_vib_init(sb_vibration *v, const sb_vib_consts *c, const double phase_rad[4])
{
    memset(v, 0, sizeof *v);
    v->c = *c;
    memcpy(v->phase_rad, phase_rad, sizeof v->phase_rad);
    for (int i = 0; i < 4; i++) {
        /* U w^2 (cos psi, spin sin psi, 0) = Re(U w^2 (1, -j spin, 0) e^{j psi}):
         * a CCW rotor's heavy side turns from forward toward left */
        const double imb_re[3] = {1.0, 0.0, 0.0}, imb_im[3] = {0.0, -c->spin_cw[i], 0.0};
        unit_response(c, c->hub_frd_m[i], imb_re, imb_im, &v->imbalance[i]);
        /* thrust ripple along the thrust axis, -z FRD */
        const double rip_re[3] = {0.0, 0.0, -1.0}, zero[3] = {0.0, 0.0, 0.0};
        unit_response(c, c->hub_frd_m[i], rip_re, zero, &v->ripple[i]);
    }
}

/* (c + j s)^k for a whole order k >= 1, by squaring: a few ulp for k <= 64, and cheaper
 * than a cos/sin pair per line. */
static void power(double c, double s, unsigned k, double *re, double *im)
{
    double rr = 1.0, ri = 0.0;
    while (k) {
        if (k & 1u) {
            const double t = rr * c - ri * s;
            ri = rr * s + ri * c;
            rr = t;
        }
        const double t = c * c - s * s;
        s = 2.0 * c * s;
        c = t;
        k >>= 1;
    }
    *re = rr;
    *im = ri;
}

/* (a + j b) *= (c + j d) */
static void cmul(double *a, double *b, double c, double d)
{
    const double t = *a * c - *b * d;
    *b = *a * d + *b * c;
    *a = t;
}

/* One line: amplitude amp [N] of unit response u at frequency w [rad/s], phasor (zr, zi)
 * at the read instant, AAF gain (hr, hi); frame mode and mount shape it, the gyro reads
 * alpha / (j w). Added to out. */
static void add_line(const sb_vib_consts *c, const sb_vib_unit *u, double amp, double w,
                     double zr, double zi, double hr, double hi, double out[6])
{
    double fr, fi, mr, mi;
    cmul(&zr, &zi, hr, hi);
    sb_vib_second_order(c->frame_hz, c->frame_damping, w, &fr, &fi);
    cmul(&zr, &zi, amp * fr, amp * fi);
    double ar = zr, ai = zi, gr = zi / w, gi = -zr / w;   /* (zr + j zi) / (j w) */
    sb_vib_second_order(c->mount_hz, c->mount_damping, w, &mr, &mi);
    cmul(&ar, &ai, mr, mi);
    sb_vib_second_order(c->mount_rot_hz, c->mount_rot_damping, w, &mr, &mi);
    cmul(&gr, &gi, mr, mi);
    for (int i = 0; i < 3; i++) {   /* Re((ar + j ai)(p_re + j p_im)) */
        out[i] += ar * u->p_re[i] - ai * u->p_im[i];
        out[i + 3] += gr * u->al_re[i] - gi * u->al_im[i];
    }
}

void sb_vib_step(sb_vibration *v, const double omega[4], double dt_s,
                 const sb_imu_chip *chip, double out[6])
{
    const sb_vib_consts *c = &v->c;
    for (int i = 0; i < 4; i++) {
        const double w = omega[i];
        const double psi = fmod(v->phase_rad[i] + w * dt_s, TWO_PI);
        v->phase_rad[i] = psi;
        if (!(w > 0.0))
            continue;   /* a stopped rotor forces nothing */
        const double cp = cos(psi), sp = sin(psi);
        /* the chip's z^-1 at the rotor frequency; order k: its k-th power */
        const double th = w / chip->odr_hz, ct = cos(th), st = -sin(th);
        double hr, hi;
        const double w2 = w * w;
        if (c->imbalance_kg_m[i] > 0.0) {
            sb_chip_gain_z(chip, ct, st, &hr, &hi);
            add_line(c, &v->imbalance[i], c->imbalance_kg_m[i] * w2, w, cp, sp, hr, hi, out);
        }
        const double thrust = c->kt_n_s2 * w2;
        for (int h = 0; h < SB_VIB_RIPPLES; h++) {
            const double k = c->ripple_order[h], frac = c->ripple_frac[h];
            if (!(k > 0.0) || !(frac > 0.0))
                continue;
            double zr, zi, zc, zs;
            power(cp, sp, (unsigned)k, &zr, &zi);
            power(ct, st, (unsigned)k, &zc, &zs);
            sb_chip_gain_z(chip, zc, zs, &hr, &hi);
            add_line(c, &v->ripple[i], frac * thrust, k * w, zr, zi, hr, hi, out);
        }
    }
}
