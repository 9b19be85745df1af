/*
 * battery.h - the physics-side battery pack (issue 28), in plain C: N lithium-polymer cells
 * in series, each with its own state of charge, open-circuit offset and resistance
 * multiplier (a weak_cell fault), one pack temperature, and the load the ESCs put on it.
 * The step kernel runs it at its report rate ([battery] rate_hz, 10 Hz) and writes the
 * BATTERY record in the step, so a report needs no Python (issue 25). Python configures it
 * (bridge/battery/), switches its faults and reads its state; the readable reference with
 * the same formulas in the same order is tests/bridge/battery_reference.py, and the kernel
 * is built without FP contraction so both give the same doubles.
 *
 * Cell (M. Chen and G. A. Rincon-Mora, IEEE Trans. Energy Conversion 21(2), 2006):
 *   open circuit, eq. (8):  V_oc = -1.031 exp(-35 SoC) + 3.685 + 0.2156 SoC - 0.1178 SoC^2
 *                                  + 0.3201 SoC^3 [V]  (4.10 V full, 2.65 V empty, the knee
 *                                  below ~15 %);
 *   resistance against charge: R_s = 0.1562 exp(-24.37 SoC) + 0.07446 ohm, as a ratio to
 *                                  its full-charge value (x1.6 at 5 %, x3.1 empty);
 *   against temperature (Arrhenius, Ea 35 kJ/mol by default, PVsyst after Lundgren 2016):
 *                                  R(T) = R(25 degC) exp(Ea / R_gas (1/T - 1/T_ref)).
 * Pack: with E the cells' summed open-circuit voltage and R their summed resistance, the
 * terminal voltage under the ESCs' input power P and the avionics current I_av solves
 * V = E - R (P / V + I_av), larger root; more power than the pack gives leaves it at E'/2.
 * Each report integrates the current by the trapezoid rule over its period and steps the
 * temperature, C dT/dt = I^2 R - (T - T_air) / R_th, exactly for a constant input.
 * Load: each ESC (lossless) draws P = (omega Ke + I_m R_w) I_m, I_m = max(0, Q) / Ke, from
 * JSBSim's rotor speed omega and shaft torque Q (bridge/battery/load.py has the derivation).
 */
#ifndef SB_PACK_H
#define SB_PACK_H

#include <stdint.h>

#include "sb_records.h"

#define SB_PACK_MAX_CELLS 14   /* what BATTERY_STATUS carries (and the scenario's max) */

/* One pack's configuration ([battery] and [esc] keys, bridge/scenario_schema.py). */
typedef struct {
    int cells;                  /* in series, 1..SB_PACK_MAX_CELLS */
    double capacity_mah;        /* nominal capacity */
    double internal_mohm;       /* pack resistance at full charge and 25 degC */
    double avionics_a;          /* current besides the ESCs */
    double initial_soc;         /* state of charge at the start, 0..1 */
    double temperature_c;       /* pack temperature at the start */
    double air_c;               /* air temperature the pack cools to */
    double activation_kj_mol;   /* Arrhenius activation energy of the resistance */
    double heat_capacity_j_k;   /* pack heat capacity */
    double thermal_k_per_w;     /* pack-to-air thermal resistance */
    double rate_hz;             /* update and BATTERY record rate */
    double ke_v_s_rad;          /* motor constant Ke = Kt [V s/rad] */
    double winding_ohm;         /* motor winding resistance */
} sb_pack_cfg;

typedef struct {
    int on;                     /* configured: the kernel runs it */
    sb_pack_cfg c;
    double r_cell_ohm;          /* one cell's resistance at full charge, 25 degC */
    double activation_j_mol;
    double r_full;              /* the charge law's resistance at full charge [ohm] */
    double period_s;            /* 1 / rate_hz: the time one report advances */
    int64_t m, next_ns;         /* report m is due at next_ns (lowrate.py due_ns) */
    uint32_t seq;               /* BATTERY records written */
    double soc[SB_PACK_MAX_CELLS];       /* state of charge, 0..1 */
    double offset_v[SB_PACK_MAX_CELLS];  /* weak_cell: open-circuit voltage lost [V] */
    double r_scale[SB_PACK_MAX_CELLS];   /* weak_cell: resistance multiplier */
    double cell_v[SB_PACK_MAX_CELLS];    /* cell terminal voltages at the last report [V] */
    double temp_c;              /* pack temperature [degC] */
    double consumed_mah;        /* charge drawn (faults lose none of it) */
    double voltage_v;           /* terminal voltage at the last report [V] */
    double current_a;           /* pack current at the last report [A] */
    double esc_w;               /* the ESCs' input power for the due report [W] (set_load) */
} sb_pack;

/* The electrical state under a load, without advancing time. */
typedef struct {
    double voltage_v, current_a, r_ohm;
    double cell_v[SB_PACK_MAX_CELLS];
} sb_pack_solution;

/* A defined pack from cfg; -1 (pack off) if cfg is out of range. */
int sb_pack_init(sb_pack *b, const sb_pack_cfg *c);

static inline int sb_pack_due(const sb_pack *b, int64_t sim_ns)
{
    return b->on && sim_ns >= b->next_ns;
}

/* Each ESC's input power [W] from rotor speeds [rad/s] and shaft torques [lbf ft]. */
void sb_pack_esc_power(const sb_pack *b, const double omega_rad_s[4],
                          const double torque_lbf_ft[4], double power_w[4]);

/* The pack under the ESCs' total input power esc_w now. */
void sb_pack_solve(const sb_pack *b, double esc_w, sb_pack_solution *out);

/* Advance one period with the ESCs' power now (the trapezoid's end point). */
void sb_pack_update(sb_pack *b, double esc_w);

/* The due report: advance by one period with b->esc_w, write the BATTERY record (header
 * flags 0) and move the schedule on. */
void sb_pack_report(sb_pack *b, sb_record *r, int64_t sim_ns);

/* Faults: cell i's open-circuit loss and resistance multiplier (0, 1: healthy); a fraction
 * of every cell's remaining charge gone at once (consumed_mah unchanged). */
int sb_pack_set_cell(sb_pack *b, int cell, double offset_v, double r_scale);
void sb_pack_lose_charge(sb_pack *b, double fraction);

/* Charge left over the nominal capacity, 0..1: the lowest cell's. */
double sb_pack_remaining(const sb_pack *b);

#endif /* SB_PACK_H */
