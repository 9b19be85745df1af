"""The FC's battery monitor: it reads the bridge's physics-side pack (BATTERY records).

The pack is simulated on the physics side (bridge/battery/), so every autopilot on the same
physics reads the same voltage and current. The record router keeps the latest BATTERY
record (fc_sil/ext/record_batch.c; over MAVLink HIL it is rebuilt from the bridge's
BATTERY_STATUS, mavlink/hil/hil_codec.py); ``read(core)`` takes it once per supervisor
step. Like a smart battery (ArduPilot's BATT_MONITOR 7, SMBus) the pack reports its state
of charge; remaining capacity is that fraction of BATT_CAPACITY, the capacity the FC is
told (the scenario's [battery] capacity_mah and BATT_CAPACITY are both 3300 mAh by
default). Until the first record arrives the monitor is not ``valid``: voltage 0, current
and consumption -1 (MAVLink's "not measured"), and the battery failsafe waits.

Parameters (fc_params.def): BATT_CAPACITY. Failsafe thresholds are read by failsafe.py.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class BatteryConfig:
    capacity_mah: float = 3300.0

    @classmethod
    def from_params(cls, get) -> "BatteryConfig":
        return cls(capacity_mah=float(get("BATT_CAPACITY")))


class BatteryMonitor:
    """The latest report of the bridge's pack; read voltage_v, current_a, consumed_mah,
    remaining_pct, remaining_mah, temperature_c, lowest_cell_v, cells."""

    def __init__(self, cfg: BatteryConfig):
        self.cfg = cfg
        self.valid = False
        self.sim_ns = -1
        self.voltage_v = 0.0
        self.current_a = -1.0
        self.consumed_mah = -1.0
        self.remaining = 1.0          # state of charge the pack reports, 0..1
        self.temperature_c = 0.0
        self.lowest_cell_v = 0.0
        self.cells = 0

    def configure(self, cfg: BatteryConfig) -> None:
        self.cfg = cfg

    def read(self, core) -> None:
        """Take the newest BATTERY record the FC core's router kept (Core.battery())."""
        count, sim_ns, v, i, mah, rem, temp, low, cells = core.battery()
        if count == 0:
            return
        self.valid = True
        self.sim_ns = sim_ns
        self.voltage_v, self.current_a, self.consumed_mah = v, i, mah
        self.remaining, self.temperature_c = rem, temp
        self.lowest_cell_v, self.cells = low, cells

    @property
    def remaining_pct(self) -> int:
        """-1 when the capacity is not tracked (BATT_CAPACITY 0) or nothing was reported yet,
        as ArduPilot reports it."""
        if self.cfg.capacity_mah <= 0 or not self.valid:
            return -1
        return int(round(100.0 * self.remaining))

    @property
    def remaining_mah(self) -> float:
        return max(0.0, self.remaining * self.cfg.capacity_mah)
