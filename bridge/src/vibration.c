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
    v->wash.rng = (uint64_t)c->wash_seed;
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

/* splitmix64 (Steele, Lea and Flood 2014): a counter through a bijective mix, so the n-th
 * draw depends only on the seed and n. */
static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Two standard normal draws (Box-Muller on two uniforms in (0, 1]). */
static void normal_pair(uint64_t *state, double *n0, double *n1)
{
    const double u1 = (double)((splitmix64(state) >> 11) + 1u) * 0x1.0p-53;
    const double u2 = (double)((splitmix64(state) >> 11) + 1u) * 0x1.0p-53;
    const double r = sqrt(-2.0 * log(u1));
    *n0 = r * cos(TWO_PI * u2);
    *n1 = r * sin(TWO_PI * u2);
}

/* The 2nd-order low-pass of sb_vib_second_order at a step of dt_s: bilinear, pre-warped so
 * the natural frequency sits where the continuous one does; f_hz <= 0: off (y = x). */
static void lp3_init(sb_vib_lp3 *f, double f_hz, double zeta, double dt_s)
{
    memset(f, 0, sizeof *f);
    if (!(f_hz > 0.0))
        return;
    const double k = tan(0.5 * TWO_PI * f_hz * dt_s), norm = 1.0 / (1.0 + 2.0 * zeta * k + k * k);
    f->on = 1;
    f->b0 = k * k * norm;
    f->b1 = 2.0 * f->b0;
    f->b2 = f->b0;
    f->a1 = 2.0 * (k * k - 1.0) * norm;
    f->a2 = (1.0 - 2.0 * zeta * k + k * k) * norm;
}

static void lp3_run(sb_vib_lp3 *f, double x[3])
{
    if (!f->on)
        return;
    for (int i = 0; i < 3; i++) {
        const double y = f->b0 * x[i] + f->s1[i];
        f->s1[i] = f->b1 * x[i] - f->a1 * y + f->s2[i];
        f->s2[i] = f->b2 * x[i] - f->a2 * y;
        x[i] = y;
    }
}

/* One step of prop wash (vibration.h): four thrust draws, the rigid-frame map, frame mode,
 * leaky integration, mount; the IMU's acceleration and angular velocity added to out. */
static void wash_step(sb_vibration *v, const double omega[4], double dt_s, double out[6])
{
    const sb_vib_consts *c = &v->c;
    sb_vib_wash *s = &v->wash;
    if (s->dt_s != dt_s) {   /* the first step: the filters for this step length */
        s->dt_s = dt_s;
        s->leak = exp(-TWO_PI * SB_VIB_WASH_HP_HZ * dt_s);
        lp3_init(&s->frame_a, c->frame_hz, c->frame_damping, dt_s);
        lp3_init(&s->frame_al, c->frame_hz, c->frame_damping, dt_s);
        lp3_init(&s->mount_t, c->mount_hz, c->mount_damping, dt_s);
        lp3_init(&s->mount_r, c->mount_rot_hz, c->mount_rot_damping, dt_s);
    }
    double n[4];   /* always four draws a step, so the stream does not depend on the speeds */
    normal_pair(&s->rng, &n[0], &n[1]);
    normal_pair(&s->rng, &n[2], &n[3]);
    double a[3] = {0.0, 0.0, 0.0}, al[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < 4; i++) {
        const double w = omega[i];
        if (!(w > 0.0))
            continue;
        const double dthrust = c->wash_frac * c->kt_n_s2 * w * w * n[i];   /* [N] */
        for (int k = 0; k < 3; k++) {
            a[k] += dthrust * v->ripple[i].p_re[k];
            al[k] += dthrust * v->ripple[i].al_re[k];
        }
    }
    lp3_run(&s->frame_a, a);
    lp3_run(&s->frame_al, al);
    double vel[3], rate[3];
    for (int k = 0; k < 3; k++) {
        s->vel[k] = s->leak * s->vel[k] + a[k] * dt_s;
        s->rate[k] = s->leak * s->rate[k] + al[k] * dt_s;
        vel[k] = s->vel[k];
        rate[k] = s->rate[k];
    }
    lp3_run(&s->mount_t, vel);
    lp3_run(&s->mount_r, rate);
    for (int k = 0; k < 3; k++) {
        out[k] += (vel[k] - s->vel_prev[k]) / dt_s;
        out[k + 3] += rate[k];
        s->vel_prev[k] = vel[k];
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
    if (c->wash_frac > 0.0 && dt_s > 0.0)   /* over no time (a read of the lines alone), none */
        wash_step(v, omega, dt_s, out);
}
