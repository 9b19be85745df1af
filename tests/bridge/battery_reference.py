"""The physics-side battery in plain Python: the reference (oracle) of the C pack
(bridge/src/battery.c), which production runs inside the step kernel. Same formulas in the
same operation order; tests/bridge/test_battery.py checks that both give the same bits, and
the step kernel's oracle (step_kernel_oracle.py) runs this one. The model and its sources
are documented in bridge/src/battery.h.

Pack: N cells in series, each with its own state of charge, open-circuit offset and
resistance multiplier (a weak_cell fault). Terminal voltage of a cell under current I:
    V_i = V_oc(SoC_i) - offset_i - I R_i,  R_i = R_cell x soc factor x temperature factor
With E the cells' summed open-circuit voltage and R their summed resistance, V = E - R (P /
V + I_av) is solved for its larger root. Temperature: C dT/dt = I^2 R - (T - T_air) / R_th,
stepped exactly over each update; charge: the trapezoid rule over the update's period.
"""

from __future__ import annotations

import math


def _sum(xs) -> float:
    """Left to right from 0.0, as the C pack adds (Python 3.12's sum() of floats adds with
    compensation and would differ in the last bit)."""
    total = 0.0
    for x in xs:
        total += x
    return total


T_REF_K = 298.15        # the temperature the scenario's resistance is given at (25 degC)
R_GAS = 8.314           # J/(mol K)
_C_K = 273.15


def ocv_v(soc: float) -> float:
    """Open-circuit voltage of one cell [V] at state of charge soc (clamped to 0..1)."""
    s = min(1.0, max(0.0, soc))
    return -1.031 * math.exp(-35.0 * s) + 3.685 + s * (0.2156 + s * (-0.1178 + s * 0.3201))


_R_FULL = 0.1562 * math.exp(-24.37) + 0.07446


def r_soc_factor(soc: float) -> float:
    """Internal resistance at soc over the resistance at full charge (Chen and Rincon-Mora)."""
    s = min(1.0, max(0.0, soc))
    return (0.1562 * math.exp(-24.37 * s) + 0.07446) / _R_FULL


def r_temp_factor(temp_c: float, activation_j_mol: float) -> float:
    """Internal resistance at temp_c over the resistance at 25 degC (Arrhenius)."""
    t_k = max(200.0, temp_c + _C_K)      # the law has no meaning near 0 K; packs never go there
    return math.exp(activation_j_mol / R_GAS * (1.0 / t_k - 1.0 / T_REF_K))


_AS_PER_MAH = 3.6


class Pack:
    """cfg: the scenario's [battery] section; air_c: the air temperature at the start."""

    def __init__(self, cfg, air_c: float):
        self.cells = int(cfg.cells)
        self.capacity_mah = float(cfg.capacity_mah)
        self.r_cell_ohm = cfg.internal_mohm * 1e-3 / self.cells
        self.avionics_a = float(cfg.avionics_a)
        self.activation_j_mol = cfg.activation_kj_mol * 1e3
        self.heat_j_k = float(cfg.heat_capacity_j_k)
        self.thermal_k_w = float(cfg.thermal_k_per_w)
        self.air_c = float(air_c)
        self.temp_c = self.air_c if cfg.temperature_c is None else float(cfg.temperature_c)
        self.soc = [float(cfg.initial_soc)] * self.cells
        self.offset_v = [0.0] * self.cells          # weak_cell: open-circuit voltage lost
        self.r_scale = [1.0] * self.cells           # weak_cell: resistance multiplier
        self.consumed_mah = 0.0                     # charge drawn (faults lose none of it)
        self.current_a = self.avionics_a
        self.cell_v = [0.0] * self.cells
        self.voltage_v = self.solve(0.0)[0]

    # --- the electrical state for a load, without advancing time --------------------------
    def _cell_r(self) -> list:
        rt = self.r_cell_ohm * r_temp_factor(self.temp_c, self.activation_j_mol)
        return [rt * r_soc_factor(s) * k for s, k in zip(self.soc, self.r_scale)]

    def solve(self, esc_power_w: float) -> tuple:
        """(terminal voltage [V], pack current [A], cell terminal voltages [V], pack
        resistance [ohm]) under the ESCs' total input power now."""
        emf = [ocv_v(s) - d for s, d in zip(self.soc, self.offset_v)]
        rs = self._cell_r()
        r = _sum(rs)
        e = _sum(emf) - r * self.avionics_a
        disc = e * e - 4.0 * r * esc_power_w
        if disc <= 0.0:
            v = max(0.0, e / 2.0)
        else:
            v = 0.5 * (e + math.sqrt(disc))
        i = self.avionics_a + (esc_power_w / v if v > 0.0 else 0.0)
        return v, i, [max(0.0, em - i * ri) for em, ri in zip(emf, rs)], r

    # --- time ------------------------------------------------------------------------------
    def update(self, esc_power_w: float, dt_s: float) -> None:
        """Advance by dt_s with the ESCs' input power now (the trapezoid's end point)."""
        _, i, _, r = self.solve(esc_power_w)
        i_mean = 0.5 * (i + self.current_a)
        self._draw(i_mean * dt_s / _AS_PER_MAH)
        self._heat(i_mean * i_mean * r, dt_s)
        self.voltage_v, self.current_a, self.cell_v, _ = self.solve(esc_power_w)

    def _draw(self, mah: float) -> None:
        self.consumed_mah += mah
        d = mah / self.capacity_mah
        self.soc = [max(0.0, s - d) for s in self.soc]

    def _heat(self, heat_w: float, dt_s: float) -> None:
        target = self.air_c + heat_w * self.thermal_k_w
        tau = self.heat_j_k * self.thermal_k_w
        self.temp_c = target + (self.temp_c - target) * math.exp(-dt_s / tau)

    # --- faults (bridge/battery/faults.py) ---------------------------------------------------
    def lose_charge(self, fraction: float) -> None:
        """A fraction of every cell's remaining charge is gone (not drawn: consumed stays)."""
        self.soc = [s * (1.0 - fraction) for s in self.soc]

    @property
    def remaining(self) -> float:
        """Charge left over the nominal capacity, 0..1: the lowest cell's (a series pack is
        empty when its first cell is)."""
        return min(self.soc)

    @property
    def lowest_cell_v(self) -> float:
        return min(self.cell_v)


# --- the load and the record, as bridge/battery/ wrote them before issue 25 moved them -----
_LBFFT_NM = 1.0 / 0.7375621           # lbf ft -> N m (motors.xml's factor)
WEAK_CELL = 0


def esc_power_w(omega, torque_lbf_ft, ke: float, r_ohm: float) -> list:
    """Each ESC's input power [W] from rotor speeds [rad/s] and shaft torques [lbf ft]."""
    out = []
    for w, q in zip(omega, torque_lbf_ft):
        w = max(0.0, w)
        i_m = max(0.0, q * _LBFFT_NM) / ke
        out.append((w * ke + i_m * r_ohm) * i_m)
    return out


def apply_fault(pack, fault, on: bool) -> None:
    """The battery unit's faults on the reference pack (bridge/battery/faults.py's meaning)."""
    p = fault.params
    if fault.type == "weak_cell":
        pack.offset_v[WEAK_CELL] = float(p["cell_drop_v"]) if on else 0.0
        pack.r_scale[WEAK_CELL] = float(p["r_scale"]) if on else 1.0
    elif fault.type == "capacity_loss" and on:
        pack.lose_charge(float(p["fraction"]))


def quantised_cells_mv(cell_v) -> list:
    """Cell voltages as BATTERY_STATUS carries them: whole mV, 0..65534 (65535 = no cell)."""
    return [min(65534, max(0, round(v * 1000.0))) for v in cell_v]


def record_fields(p: Pack, seq: int, sim_ns: int) -> tuple:
    """The BATTERY record of the pack's last update (shm/records.py field order)."""
    from silbridge.shm.records import KIND_BATTERY
    mv = quantised_cells_mv(p.cell_v)
    return (KIND_BATTERY, 0, seq & 0xFFFFFFFF, sim_ns, 0, _sum(mv) / 1000.0,
            round(p.current_a * 100.0) / 100.0, float(round(p.consumed_mah)),
            round(p.remaining * 100.0) / 100.0, round(p.temp_c * 100.0) / 100.0,
            min(mv) / 1000.0, p.cells)


class KernelPack:
    """The step kernel's pack (bridge/src/step_battery.c's methods) on this reference: what
    the oracle kernel (step_kernel_oracle.py) runs. torque: the motors' torque getters."""

    def __init__(self, torque, cells, capacity_mah, internal_mohm, avionics_a, initial_soc,
                 temperature_c, air_c, activation_kj_mol, heat_capacity_j_k, thermal_k_per_w,
                 rate_hz, ke_v_s_rad, winding_ohm):
        from types import SimpleNamespace
        cfg = SimpleNamespace(cells=cells, capacity_mah=capacity_mah, internal_mohm=internal_mohm,
                              avionics_a=avionics_a, initial_soc=initial_soc,
                              temperature_c=temperature_c, activation_kj_mol=activation_kj_mol,
                              heat_capacity_j_k=heat_capacity_j_k,
                              thermal_k_per_w=thermal_k_per_w)
        self.pack = Pack(cfg, air_c)
        self.torque = list(torque)
        self.ke, self.r_ohm = ke_v_s_rad, winding_ohm
        self.rate_hz = rate_hz
        self.period_s = 1.0 / rate_hz
        self.m, self.next_ns, self.seq = 1, _due_ns(1, rate_hz), 0

    def due(self, sim_ns: int) -> bool:
        return sim_ns >= self.next_ns

    def esc_power(self, omega) -> tuple:
        return tuple(esc_power_w(omega, [f() for f in self.torque], self.ke, self.r_ohm))

    def report(self, buf, slot: int, sim_ns: int, omega) -> None:
        """Advance by one period under the load now; the BATTERY record at slot."""
        from silbridge.shm.records import Kind, record_struct
        self.pack.update(_sum(self.esc_power(omega)), self.period_s)
        self.m += 1
        self.next_ns = _due_ns(self.m, self.rate_hz)
        record_struct(Kind.BATTERY).pack_into(buf, slot * 64,
                                              *record_fields(self.pack, self.seq, sim_ns))
        self.seq += 1

    def state(self) -> tuple:
        p = self.pack
        return (p.voltage_v, p.current_a, p.consumed_mah, p.remaining, p.temp_c,
                min(p.cell_v), self.seq, self.next_ns)

    def solve(self, esc_w: float) -> tuple:
        return self.pack.solve(esc_w)[:2]

    def set_cell(self, cell: int, offset_v: float, r_scale: float) -> None:
        self.pack.offset_v[cell] = offset_v
        self.pack.r_scale[cell] = r_scale


def _due_ns(m: int, rate_hz: float) -> int:
    return int(round(m * 1e9 / rate_hz))
