"""The battery pack: N cells in series, each with its own state, and the pack's temperature.

Per cell: state of charge, an open-circuit offset and a resistance multiplier (both neutral
unless a weak_cell fault sets them), so one cell can sit lower and sag more than the rest.
The cells carry one current (series). Terminal voltage of a cell under current I:
    V_i = V_oc(SoC_i) - offset_i - I R_i,  R_i = R_cell x soc factor x temperature factor
(bridge/battery/cell.py). The load is the ESCs' input power P (bridge/battery/load.py) plus
the avionics current; with E = sum of the cells' open-circuit voltages and R their summed
resistance, V = E - R (P / V + I_av) is solved for its larger root (the other is the
collapsed pack). More power than the pack can give leaves it at E' / 2 (its maximum-power
point); that is a browned-out vehicle, not a state this model follows further.

Temperature, first order: C dT/dt = I^2 R - (T - T_air) / R_th, stepped exactly for a
constant input over each update. Charge: each update integrates the current by the
trapezoid rule over its period (the update rate is the report rate, 10 Hz: see
docs/explanation/battery.md for the measured error against per-step integration).
"""

from __future__ import annotations

import math

from silbridge.bridge.battery.cell import ocv_v, r_soc_factor, r_temp_factor

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
        r = sum(rs)
        e = sum(emf) - r * self.avionics_a
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
