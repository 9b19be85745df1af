/*
 * gnss_model.c - a GNSS epoch (gnss_model.h). Every expression follows lowrate.py's in
 * operand order, so that the doubles, and so the record's bytes, are Python's: a
 * reordered sum or product would round differently.
 */
#include "gnss_model.h"

#include <math.h>
#include <string.h>

#include "step_maths.h"

/* math.degrees(x) is x * (180 / pi), the quotient rounded once, as CPython computes it. */
static const double RAD_TO_DEG = 180.0 / 3.14159265358979323846;

/* int(round(x)): Python rounds half to even, as nearbyint does in the default mode. */
static int32_t round_i32(double x)
{
    return (int32_t)nearbyint(x);
}

/* Gnss.epoch's Gauss-Markov position error: drawn from its stationary law at the first
 * epoch, then a = exp(-dt / tau), err = a err + sqrt(1 - a^2) sigma n. */
static void update_error(sb_gnss_model *g, const double *n, int64_t sim_ns)
{
    const double *sig = g->c.sigma_ned_m;
    if (!g->have_err) {
        for (int i = 0; i < 3; i++)
            g->err_ned_m[i] = sig[i] * n[i];
        g->have_err = 1;
    } else {
        const double a = exp((double)(-(sim_ns - g->last_epoch_ns)) * 1e-9 / g->c.tau_s);
        const double q = sqrt(1.0 - a * a);
        for (int i = 0; i < 3; i++)
            g->err_ned_m[i] = a * g->err_ned_m[i] + q * sig[i] * n[i];
    }
    g->last_epoch_ns = sim_ns;
}

int sb_gnss_epoch(sb_gnss_model *g, const sb_gnss_truth *t, int64_t sim_ns, sb_record *r)
{
    const double *n = sb_lowrate_take(&g->lr, 6);
    if (n == NULL)
        return -1;
    update_error(g, n, sim_ns);
    const sb_gnss_cfg *c = &g->c;
    const double *e = g->err_ned_m;
    memset(r, 0, sizeof *r);
    r->h.kind = SB_KIND_GNSS;
    r->h.seq = g->lr.seq++;
    sb_gnss *f = &r->u.gnss;
    f->lat_e7 = round_i32((t->lat_rad + e[0] / c->m_per_rad_lat) * RAD_TO_DEG * 1e7);
    f->lon_e7 = round_i32((t->lon_rad + e[1] / c->m_per_rad_lon) * RAD_TO_DEG * 1e7);
    f->alt_mm = round_i32((c->ground_alt_m + t->hagl_m - e[2]) * 1000.0);
    for (int i = 0; i < 3; i++)
        f->vel_ned_m_s[i] =
            (float)sb_quant_velocity_m_s(t->vel_ned_m_s[i] + c->vel_sigma_m_s * n[3 + i]);
    f->eph_cm = c->eph_cm;
    f->epv_cm = c->epv_cm;
    f->fix_type = c->fix_type;
    f->satellites = c->satellites;
    return sb_lowrate_spent(&g->lr);
}
