"""ESC telemetry: what each ESC of the quadx reports about its motor, at a declared rate.

Off unless the scenario sets ``[esc] telemetry_hz`` (then S1..S4, which do not, publish the
same records as before). When on, every ``1 / telemetry_hz`` of simulated time the bridge
publishes one ESC record per motor (shm/records.py ``ESC_DTYPE``), as BLHeli_32 serial
telemetry and bidirectional DShot report per ESC: rotor speed, the pack voltage the ESC sees,
its battery-side current, its temperature and the charge it has drawn.

Where the numbers come from (keys and cited defaults in bridge/scenario_schema.py, [esc]):
- rpm: JSBSim's motor model, ``fcs/mN-omega-rad_s`` after the step (60 / 2 pi rad/s).
- current: each ESC's input power P (the DC-motor equivalent of the 2212 920KV motor,
  bridge/battery/load.py) over the pack voltage: I = P / V_pack.
- voltage: the physics-side pack (bridge/src/battery.h, the one every autopilot reads)
  under the present load of all ESCs plus the avionics, solved for the sag the currents
  themselves cause; the pack's charge and temperature advance at its own report rate.
- temperature: a first-order rise towards ambient + k x (power through the ESC), time
  constant tau, from the air temperature JSBSim gives at the start.
Values are quantised at the source to what the ESC reports and what the HIL link's
ESC_TELEMETRY_1_TO_4 carries exactly: whole rpm, 0.01 V, 0.01 A, whole degC (0..255),
whole mAh; so the FC gets the same numbers over shared memory and over MAVLink.
"""

from __future__ import annotations

import math

from silbridge.bridge.battery.load import RPM_PER_RAD_S
from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.lowrate import Schedule
from silbridge.shm.records import KIND_ESC, Kind, record_struct

SLOT = record_struct(Kind.ESC)        # the whole 64-byte ESC slot (shm/records.py)
MOTORS = 4
_MAH_PER_AS = 1000.0 / 3600.0
_U16 = 65535


def enabled(scenario) -> bool:
    """True when the scenario asks for ESC telemetry ([esc] telemetry_hz set)."""
    return scenario.esc.telemetry_hz is not None


class EscTelemetry:
    """The ESCs of one flight: ``due(sim_ns)`` says whether an epoch is due at this physics
    step; ``write(buf, offset, seq0, sim_ns, dt_s)`` writes its MOTORS records."""

    def __init__(self, cfg, physics_hz: int, ambient_c: float, load, pack):
        rate = float(cfg.telemetry_hz)
        if not rate > 0.0:      # the schema refuses it too; a direct caller gets the same words
            raise ScenarioError(f"esc.telemetry_hz must be > 0 Hz, got {rate:g}")
        if rate > physics_hz:
            raise ScenarioError(f"esc.telemetry_hz = {rate:g} Hz is above the physics rate "
                                f"{physics_hz} Hz: reports are made once per physics step "
                                "at most; lower it or raise physics.rate_hz")
        self.schedule = Schedule(rate)
        self.period_s = 1.0 / rate
        self._load = load              # bridge/battery/load.py: each ESC's input power
        self._pack = pack              # bridge/battery Battery: the one pack (solve, voltage_v)
        self._k_per_w = float(cfg.temp_k_per_w)
        self._tau_s = float(cfg.temp_tau_s)
        self._ambient_c = float(ambient_c)
        self.temp_c = [self._ambient_c] * MOTORS
        self.mah = [0.0] * MOTORS
        self.current_a = [0.0] * MOTORS
        self.rpm = [0.0] * MOTORS
        self.voltage_v = pack.voltage_v
        self.epochs = 0

    def due(self, sim_ns: int) -> bool:
        return sim_ns >= self.schedule.next_ns

    def update(self) -> None:
        """Advance the electrical and thermal state by one report period (the values the
        ESCs report at this epoch)."""
        omega = self._load.omega_rad_s()
        p_in = self._load.power_w(omega)
        v = self._pack.solve(sum(p_in))[0]
        dt = self.period_s
        decay = 1.0 - math.exp(-dt / self._tau_s)
        for m in range(MOTORS):
            i = p_in[m] / v if v > 0.0 else 0.0
            self.current_a[m] = i
            self.mah[m] += i * dt * _MAH_PER_AS
            target = self._ambient_c + self._k_per_w * p_in[m]
            self.temp_c[m] += (target - self.temp_c[m]) * decay
        self.voltage_v = v
        self.rpm = [w * RPM_PER_RAD_S for w in omega]

    def write(self, buf, offset: int, seq0: int, sim_ns: int) -> int:
        """Update, then pack this epoch's MOTORS records at offset; returns MOTORS."""
        self.update()
        self.schedule.advance()
        self.epochs += 1
        v = _quant(self.voltage_v, 100.0)
        for m in range(MOTORS):
            temp = float(min(255, max(0, round(self.temp_c[m]))))
            SLOT.pack_into(buf, offset + m * SLOT.size, KIND_ESC, 0, (seq0 + m) & 0xFFFFFFFF,
                           sim_ns, 0, m, MOTORS, 0, float(min(_U16, round(self.rpm[m]))), v,
                           _quant(self.current_a[m], 100.0), temp,
                           float(min(_U16, round(self.mah[m]))))
        return MOTORS


def _quant(x: float, per_unit: float) -> float:
    """x to the nearest 1/per_unit (0.01 V, 0.01 A), within ESC_TELEMETRY's u16."""
    return min(_U16, max(0, round(x * per_unit))) / per_unit
