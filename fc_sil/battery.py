"""A simple battery model for the SIL vehicle: what a power module would measure.

The bridge simulates no battery, so the FC models one from its own motor outputs, as a
power module would see it: current = avionics + per-motor current that grows with throttle
to the 1.5 power (propeller power ~ thrust^1.5, thrust ~ throttle), consumed charge by
integration, and terminal voltage = open-circuit voltage of the remaining charge minus the
sag I*R. The open-circuit curve is linear from 4.2 V (full) to 3.3 V (empty) per cell: crude
but monotonic, so the voltage falls with use and sags under load as a real pack does.

Parameters (fc_params.def): BATT_CAPACITY, SB_BATT_CELLS, SB_BATT_R_MOHM, SB_BATT_I_MOT,
SB_BATT_I_IDLE. Failsafe thresholds are read by failsafe.py, not here.
"""

from __future__ import annotations

from dataclasses import dataclass

CELL_FULL_V = 4.2
CELL_EMPTY_V = 3.3


@dataclass
class BatteryConfig:
    capacity_mah: float = 3300.0
    cells: int = 4
    r_ohm: float = 0.025
    i_motor_full_a: float = 18.0
    i_idle_a: float = 0.6

    @classmethod
    def from_params(cls, get) -> "BatteryConfig":
        return cls(capacity_mah=float(get("BATT_CAPACITY")), cells=int(get("SB_BATT_CELLS")),
                   r_ohm=float(get("SB_BATT_R_MOHM")) * 1e-3,
                   i_motor_full_a=float(get("SB_BATT_I_MOT")),
                   i_idle_a=float(get("SB_BATT_I_IDLE")))


class BatteryModel:
    """Integrates current from PWM outputs; read voltage_v, current_a, consumed_mah."""

    def __init__(self, cfg: BatteryConfig, pwm_min_us: float = 1000.0,
                 pwm_max_us: float = 2000.0):
        self.cfg = cfg
        self.pwm_min_us = pwm_min_us
        self.pwm_max_us = pwm_max_us
        self.consumed_mah = 0.0
        self.current_a = cfg.i_idle_a
        self.voltage_v = self._ocv() - self.current_a * cfg.r_ohm

    def configure(self, cfg: BatteryConfig, pwm_min_us: float, pwm_max_us: float) -> None:
        self.cfg = cfg
        self.pwm_min_us, self.pwm_max_us = pwm_min_us, pwm_max_us

    def _soc(self) -> float:
        cap = self.cfg.capacity_mah
        if cap <= 0:
            return 1.0
        return min(1.0, max(0.0, 1.0 - self.consumed_mah / cap))

    def _ocv(self) -> float:
        return self.cfg.cells * (CELL_EMPTY_V + (CELL_FULL_V - CELL_EMPTY_V) * self._soc())

    def update(self, pwm_us, dt_s: float) -> None:
        """Advance by dt_s with the given motor outputs [us]."""
        span = max(1.0, self.pwm_max_us - self.pwm_min_us)
        i = self.cfg.i_idle_a
        for us in pwm_us:
            thr = min(1.0, max(0.0, (float(us) - self.pwm_min_us) / span))
            i += self.cfg.i_motor_full_a * thr ** 1.5
        self.current_a = i
        self.consumed_mah += i * dt_s * (1000.0 / 3600.0)
        self.voltage_v = max(0.0, self._ocv() - i * self.cfg.r_ohm)

    @property
    def remaining_pct(self) -> int:
        """-1 when the capacity is not tracked (BATT_CAPACITY 0), as ArduPilot reports it."""
        if self.cfg.capacity_mah <= 0:
            return -1
        return int(round(100.0 * self._soc()))

    @property
    def remaining_mah(self) -> float:
        return max(0.0, self.cfg.capacity_mah - self.consumed_mah)
