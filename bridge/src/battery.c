/*
 * battery.c - see battery.h. Every expression keeps the association and the order of the
 * reference (tests/bridge/battery_reference.py), sums run left to right from 0.0 as
 * Python 3.11's sum() does, max(a, x) is "x > a ? x : a" as Python's max keeps its first
 * argument on ties and NaN, and quantities are rounded half to even (nearbyint) as round().
 */
#include "battery.h"

#include <math.h>
#include <string.h>

#include "step_maths.h"

#define T_REF_K 298.15      /* the temperature the resistance is given at (25 degC) */
#define R_GAS 8.314         /* J/(mol K) */
#define C_K 273.15
#define AS_PER_MAH 3.6
#define LBFFT_NM (1.0 / 0.7375621)   /* lbf ft -> N m (motors.xml's factor) */

static double max_of(double a, double x)
{
    return x > a ? x : a;
}

static double min_of(double a, double x)
{
    return x < a ? x : a;
}

/* Open-circuit voltage of one cell [V] at state of charge soc (clamped to 0..1). */
static double ocv_v(double soc)
{
    const double s = min_of(1.0, max_of(0.0, soc));
    return -1.031 * exp(-35.0 * s) + 3.685 + s * (0.2156 + s * (-0.1178 + s * 0.3201));
}

static double r_soc_law(double s)
{
    return 0.1562 * exp(-24.37 * s) + 0.07446;
}

/* Internal resistance at soc over the resistance at full charge. */
static double r_soc_factor(const sb_pack *b, double soc)
{
    return r_soc_law(min_of(1.0, max_of(0.0, soc))) / b->r_full;
}

/* Internal resistance at temp_c over the resistance at 25 degC; the law has no meaning
 * near 0 K (packs never go there). */
static double r_temp_factor(double temp_c, double activation_j_mol)
{
    const double t_k = max_of(200.0, temp_c + C_K);
    return exp(activation_j_mol / R_GAS * (1.0 / t_k - 1.0 / T_REF_K));
}

int sb_pack_init(sb_pack *b, const sb_pack_cfg *c)
{
    memset(b, 0, sizeof *b);
    if (c->cells < 1 || c->cells > SB_PACK_MAX_CELLS || !(c->rate_hz > 0.0) ||
        !(c->capacity_mah > 0.0) || !(c->ke_v_s_rad > 0.0))
        return -1;
    b->c = *c;
    b->r_cell_ohm = c->internal_mohm * 1e-3 / (double)c->cells;
    b->activation_j_mol = c->activation_kj_mol * 1e3;
    /* A run-time exp, as the reference's math.exp: GCC would fold exp(-24.37) at compile
     * time (correctly rounded), which glibc's exp need not match to the last bit. */
    volatile double full = 1.0;
    b->r_full = r_soc_law(full);
    b->period_s = 1.0 / c->rate_hz;
    b->m = 1;
    b->next_ns = sb_due_ns(1, c->rate_hz);
    b->temp_c = c->temperature_c;
    for (int i = 0; i < c->cells; i++) {
        b->soc[i] = c->initial_soc;
        b->r_scale[i] = 1.0;
    }
    b->current_a = c->avionics_a;
    sb_pack_solution s;
    sb_pack_solve(b, 0.0, &s);
    b->voltage_v = s.voltage_v;     /* the cells' voltages wait for the first report */
    b->on = 1;
    return 0;
}

void sb_pack_esc_power(const sb_pack *b, const double omega_rad_s[4],
                          const double torque_lbf_ft[4], double power_w[4])
{
    const double ke = b->c.ke_v_s_rad;
    for (int m = 0; m < 4; m++) {
        const double w = max_of(0.0, omega_rad_s[m]);
        const double i_m = max_of(0.0, torque_lbf_ft[m] * LBFFT_NM) / ke;
        power_w[m] = (w * ke + i_m * b->c.winding_ohm) * i_m;
    }
}

void sb_pack_solve(const sb_pack *b, double esc_w, sb_pack_solution *out)
{
    const int n = b->c.cells;
    double emf[SB_PACK_MAX_CELLS], rs[SB_PACK_MAX_CELLS];
    const double rt = b->r_cell_ohm * r_temp_factor(b->temp_c, b->activation_j_mol);
    double emf_sum = 0.0, r = 0.0;
    for (int i = 0; i < n; i++) {
        emf[i] = ocv_v(b->soc[i]) - b->offset_v[i];
        rs[i] = rt * r_soc_factor(b, b->soc[i]) * b->r_scale[i];
    }
    for (int i = 0; i < n; i++)
        r += rs[i];
    for (int i = 0; i < n; i++)
        emf_sum += emf[i];
    const double e = emf_sum - r * b->c.avionics_a;
    const double disc = e * e - 4.0 * r * esc_w;
    double v;
    if (disc <= 0.0)
        v = max_of(0.0, e / 2.0);
    else
        v = 0.5 * (e + sqrt(disc));
    const double i = b->c.avionics_a + (v > 0.0 ? esc_w / v : 0.0);
    for (int k = 0; k < n; k++)
        out->cell_v[k] = max_of(0.0, emf[k] - i * rs[k]);
    out->voltage_v = v;
    out->current_a = i;
    out->r_ohm = r;
}

void sb_pack_update(sb_pack *b, double esc_w)
{
    sb_pack_solution s;
    sb_pack_solve(b, esc_w, &s);
    const double dt = b->period_s;
    const double i_mean = 0.5 * (s.current_a + b->current_a);
    /* the charge drawn */
    const double mah = i_mean * dt / AS_PER_MAH;
    b->consumed_mah += mah;
    const double d = mah / b->c.capacity_mah;
    for (int k = 0; k < b->c.cells; k++)
        b->soc[k] = max_of(0.0, b->soc[k] - d);
    /* the heat */
    const double heat_w = i_mean * i_mean * s.r_ohm;
    const double target = b->c.air_c + heat_w * b->c.thermal_k_per_w;
    const double tau = b->c.heat_capacity_j_k * b->c.thermal_k_per_w;
    b->temp_c = target + (b->temp_c - target) * exp(-dt / tau);
    sb_pack_solve(b, esc_w, &s);
    b->voltage_v = s.voltage_v;
    b->current_a = s.current_a;
    memcpy(b->cell_v, s.cell_v, sizeof b->cell_v);
}

/* Whole mV as BATTERY_STATUS carries a cell, 0..65534 (65535 = no cell). */
static long cell_mv(double v)
{
    const double q = nearbyint(v * 1000.0);
    return q > 0.0 ? (q < 65534.0 ? (long)q : 65534) : 0;
}

void sb_pack_report(sb_pack *b, sb_record *r, int64_t sim_ns)
{
    sb_pack_update(b, b->esc_w);
    b->next_ns = sb_due_ns(++b->m, b->c.rate_hz);
    long sum_mv = 0, low_mv = 0;
    for (int k = 0; k < b->c.cells; k++) {
        const long mv = cell_mv(b->cell_v[k]);
        sum_mv += mv;
        if (k == 0 || mv < low_mv)
            low_mv = mv;
    }
    memset(r, 0, sizeof *r);
    r->h.kind = SB_KIND_BATTERY;
    r->h.seq = b->seq++;
    r->h.sim_ns = sim_ns;
    sb_battery *q = &r->u.battery;
    q->voltage_v = (float)((double)sum_mv / 1000.0);
    q->current_a = (float)(nearbyint(b->current_a * 100.0) / 100.0);
    q->consumed_mah = (float)nearbyint(b->consumed_mah);
    q->remaining = (float)(nearbyint(sb_pack_remaining(b) * 100.0) / 100.0);
    q->temperature_c = (float)(nearbyint(b->temp_c * 100.0) / 100.0);
    q->lowest_cell_v = (float)((double)low_mv / 1000.0);
    q->cell_count = (uint8_t)b->c.cells;
}

int sb_pack_set_cell(sb_pack *b, int cell, double offset_v, double r_scale)
{
    if (cell < 0 || cell >= b->c.cells)
        return -1;
    b->offset_v[cell] = offset_v;
    b->r_scale[cell] = r_scale;
    return 0;
}

void sb_pack_lose_charge(sb_pack *b, double fraction)
{
    for (int k = 0; k < b->c.cells; k++)
        b->soc[k] = b->soc[k] * (1.0 - fraction);
}

double sb_pack_remaining(const sb_pack *b)
{
    double low = b->soc[0];
    for (int k = 1; k < b->c.cells; k++)
        low = min_of(low, b->soc[k]);
    return low;
}
