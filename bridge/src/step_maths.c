/*
 * step_maths.c - see step_maths.h. Every expression keeps the association of
 * the Python reference (a + b + c is (a + b) + c), which is what makes the two
 * bit-identical; do not "simplify" one side alone.
 */
#include "step_maths.h"

#include <math.h>

#define TWO_PI (2.0 * 3.14159265358979311600)   /* Python's 2.0 * math.pi */

/* Rotor hubs in body FRD [m] (bridge/fdm.py ROTOR_HUBS_FRD_M, from quadx.xml). */
static const double ROTOR_HUBS_FRD_M[4][3] = {
    {0.1591, 0.1591, -0.03}, {-0.1591, -0.1591, -0.03},
    {0.1591, -0.1591, -0.03}, {-0.1591, 0.1591, -0.03}};

static double clamp(double v, double lim)
{
    return v < -lim ? -lim : (v > lim ? lim : v);
}

void sb_imu_scalar(const sb_imu_consts *c, const double af[3], const double w[3],
                   const double omega[4], double phase[4], const double n[6],
                   const double j[3], double out[6])
{
    double p[4];
    for (int i = 0; i < 4; i++) {   /* rotor phases at the end of the step */
        p[i] = fmod(phase[i] + omega[i] * c->dt_s, TWO_PI);
        phase[i] = p[i];
    }
    const double va = c->vib_accel, vg = c->vib_gyro;
    double vx = 0.0, vy = 0.0, vz = 0.0;
    if (va != 0.0 || vg != 0.0) {
        const double k = c->inv_omega_max2;
        double s[4], co[4], si[4];
        for (int i = 0; i < 4; i++) {
            s[i] = omega[i] * omega[i] * k;
            co[i] = cos(p[i]);
            si[i] = sin(p[i]);
        }
        vx = s[0] * co[0] + s[1] * co[1] + s[2] * co[2] + s[3] * co[3];
        /* spin: motors 1, 2 CCW (-1), 3, 4 CW (+1) */
        vy = -s[0] * si[0] - s[1] * si[1] + s[2] * si[2] + s[3] * si[3];
        /* blade pass: sin(2p) / 2 = sin p cos p */
        vz = s[0] * si[0] * co[0] + s[1] * si[1] * co[1] + s[2] * si[2] * co[2]
           + s[3] * si[3] * co[3];
    }
    out[0] = af[0] + va * vx + n[3];
    out[1] = af[1] + va * vy + n[4];
    out[2] = af[2] + va * vz + n[5];
    out[3] = w[0] + j[0] + vg * vy + n[0];
    out[4] = w[1] + j[1] + vg * vx + n[1];
    out[5] = w[2] + j[2] + vg * vz + n[2];
    const double ra = c->range_accel, rg = c->range_gyro;
    for (int i = 0; i < 3; i++) {
        out[i] = clamp(out[i], ra);
        out[i + 3] = clamp(out[i + 3], rg);
    }
}

void sb_quat_from_euler(double phi, double theta, double psi, double q[4])
{
    const double cr = cos(0.5 * phi), sr = sin(0.5 * phi);
    const double cp = cos(0.5 * theta), sp = sin(0.5 * theta);
    const double cy = cos(0.5 * psi), sy = sin(0.5 * psi);
    q[0] = cr * cp * cy + sr * sp * sy;
    q[1] = sr * cp * cy - cr * sp * sy;
    q[2] = cr * sp * cy + sr * cp * sy;
    q[3] = cr * cp * sy - sr * sp * cy;
    if (q[0] < 0.0) {   /* JSBSim's psi is in [0, 2 pi): keep the w >= 0 hemisphere */
        for (int i = 0; i < 4; i++)
            q[i] = -q[i];
    }
}

/* nearbyint rounds half to even in the default rounding mode, as Python's round();
 * "+ 0.0" turns its -0.0 into the 0.0 Python's integer round() gives. */
double sb_quant_down_m(double d)
{
    if (d != d || isinf(d))
        return d;
    return (nearbyint(d * 1000.0) + 0.0) / 1000.0;
}

double sb_quant_velocity_m_s(double v)
{
    if (v != v)
        return v;
    double cm = isinf(v) ? v : nearbyint(v * 100.0) + 0.0;
    cm = cm < -32767.0 ? -32767.0 : (cm > 32767.0 ? 32767.0 : cm);
    return cm / 100.0;
}

int sb_rotor_strike(double phi, double theta, double hagl_m)
{
    const double sth = sin(theta), cth = cos(theta);
    const double sph_cth = sin(phi) * cth, cph_cth = cos(phi) * cth;
    for (int i = 0; i < 4; i++) {
        const double *h = ROTOR_HUBS_FRD_M[i];
        const double down_m = -sth * h[0] + sph_cth * h[1] + cph_cth * h[2];
        if (hagl_m + (-down_m) <= 0.0)
            return 1;
    }
    return 0;
}

double sb_quant_pressure_pa(double pa)
{
    if (!(pa > 0.0) || isinf(pa))
        return pa;
    const double hpa = pa / 100.0;
    int exp2;
    (void)frexp(hpa, &exp2);                  /* hpa = f * 2^exp2, 0.5 <= f < 1 */
    const double quantum = ldexp(1.0, exp2 - 17);
    return nearbyint(hpa / quantum) * quantum * 100.0;
}

int64_t sb_due_ns(int64_t m, double rate_hz)
{
    return (int64_t)nearbyint((double)m * 1e9 / rate_hz);
}

void sb_ned_to_frd(double phi, double theta, double psi, const double v[3], double out[3])
{
    const double cph = cos(phi), sph = sin(phi);
    const double cth = cos(theta), sth = sin(theta);
    const double cps = cos(psi), sps = sin(psi);
    /* yaw about down, then pitch about the new right axis, then roll about forward */
    const double x1 = cps * v[0] + sps * v[1];
    const double y1 = -sps * v[0] + cps * v[1];
    const double x2 = cth * x1 - sth * v[2];
    const double z2 = sth * x1 + cth * v[2];
    out[0] = x2;
    out[1] = cph * y1 + sph * z2;
    out[2] = -sph * y1 + cph * z2;
}
