"""The physics-side battery: one pack every autopilot reads (issue 28).

``Battery`` (``sim.battery``) joins the pack model (pack.py, cell.py) to its load (the ESCs'
input power from JSBSim's motors, load.py, plus the avionics current) and reports it: every
``1 / rate_hz`` of sim time ([battery] rate_hz, 10 Hz: ArduCopter reads its battery
monitor at 10 Hz) it advances the pack over the period and writes one BATTERY record
(shm/records.py), quantised at the source to what MAVLink's BATTERY_STATUS carries (whole
mV per cell, 0.01 A, whole mAh, whole %, 0.01 degC) so that shared memory and HIL agree.
The ESC telemetry (bridge/esc_telemetry.py) reads the same pack.
"""

from __future__ import annotations

from silbridge.bridge.battery.faults import BatteryFaults
from silbridge.bridge.battery.load import MotorLoad
from silbridge.bridge.battery.pack import Pack
from silbridge.bridge.lowrate import Schedule
from silbridge.shm.records import KIND_BATTERY, Kind, record_struct

SLOT = record_struct(Kind.BATTERY)

__all__ = ["Battery", "BatteryFaults", "MotorLoad", "Pack", "quantised_cells_mv"]


def quantised_cells_mv(cell_v) -> list:
    """Cell voltages as BATTERY_STATUS carries them: whole mV, 0..65534 (65535 = no cell)."""
    return [min(65534, max(0, round(v * 1000.0))) for v in cell_v]


class Battery:
    """The pack of one flight. Read voltage_v, current_a, consumed_mah, remaining (0..1),
    temperature_c: the pack's state at its last report."""

    def __init__(self, cfg, air_c: float, load: MotorLoad):
        self.pack = Pack(cfg, air_c)
        self.load = load
        self.schedule = Schedule(float(cfg.rate_hz))
        self.period_s = 1.0 / float(cfg.rate_hz)
        self.applier = BatteryFaults(self.pack)
        self.reports = 0

    voltage_v = property(lambda self: self.pack.voltage_v)
    current_a = property(lambda self: self.pack.current_a)
    consumed_mah = property(lambda self: self.pack.consumed_mah)
    remaining = property(lambda self: self.pack.remaining)
    temperature_c = property(lambda self: self.pack.temp_c)

    def due(self, sim_ns: int) -> bool:
        return sim_ns >= self.schedule.next_ns

    def write(self, buf, offset: int, seq: int, sim_ns: int) -> int:
        """Advance the pack by one period, pack its record at offset; returns 1."""
        self.pack.update(sum(self.load.power_w()), self.period_s)
        self.schedule.advance()
        self.reports += 1
        SLOT.pack_into(buf, offset, *self.record_fields(seq, sim_ns))
        return 1

    def record_fields(self, seq: int, sim_ns: int) -> tuple:
        p = self.pack
        mv = quantised_cells_mv(p.cell_v)
        return (KIND_BATTERY, 0, seq & 0xFFFFFFFF, sim_ns, 0, sum(mv) / 1000.0,
                round(p.current_a * 100.0) / 100.0, float(round(p.consumed_mah)),
                round(p.remaining * 100.0) / 100.0, round(p.temp_c * 100.0) / 100.0,
                min(mv) / 1000.0, p.cells)
