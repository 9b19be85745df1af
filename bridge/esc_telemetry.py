"""ESC telemetry: what each ESC of the quadx reports about its motor, at a declared rate.

Off unless the scenario sets ``[esc] telemetry_hz`` (then S1..S4, which do not, publish the
same records as before). When on, every ``1 / telemetry_hz`` of simulated time the bridge
publishes one ESC record per motor (shm/records.py ``ESC_DTYPE``), as BLHeli_32 serial
telemetry and bidirectional DShot report per ESC: rotor speed, the pack voltage the ESC sees,
its battery-side current, its temperature and the charge it has drawn.

Where the numbers come from (keys and cited defaults in bridge/scenario_schema.py, [esc]):
- rpm: JSBSim's motor model, ``fcs/mN-omega-rad_s`` after the step (60 / 2 pi rad/s).
- current: the DC-motor equivalent of the 2212 920KV motor of jsbsim_models/quadx/motors.xml.
  The model's shaft torque ``fcs/mN-torque-lbsft`` (the reaction torque JSBSim applies)
  needs the motor current I_m = Q / Kt, Kt = 60 / (2 pi KV) N m/A; the winding needs
  V_m = omega / (KV in rad/s/V) + I_m R. The ESC, a lossless buck converter here, draws
  I = V_m I_m / V_pack from the pack. No-load (iron and friction) current is neglected.
- voltage: the pack the FC models today (fc_sil/battery.py: cells x 4.2 V full to 3.3 V
  empty, linear in the charge drawn, minus the sag I R), here fed with the ESC currents plus
  the avionics current, solved for the sag the currents themselves cause.
- temperature: a first-order rise towards ambient + k x (power through the ESC), time
  constant tau, from the air temperature JSBSim gives at the start.
Values are quantised at the source to what the ESC reports and what the HIL link's
ESC_TELEMETRY_1_TO_4 carries exactly: whole rpm, 0.01 V, 0.01 A, whole degC (0..255),
whole mAh; so the FC gets the same numbers over shared memory and over MAVLink.
"""

from __future__ import annotations

import math

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.lowrate import Schedule
from silbridge.shm.records import KIND_ESC, Kind, record_struct

SLOT = record_struct(Kind.ESC)        # the whole 64-byte ESC slot (shm/records.py)
MOTORS = 4
_LBFFT_NM = 1.0 / 0.7375621           # lbf ft -> N m (motors.xml's factor)
_RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
_CELL_FULL_V = 4.2                    # the FC's pack curve (fc_sil/battery.py)
_CELL_EMPTY_V = 3.3
_MAH_PER_AS = 1000.0 / 3600.0
_U16 = 65535


def enabled(scenario) -> bool:
    """True when the scenario asks for ESC telemetry ([esc] telemetry_hz set)."""
    return scenario.esc.telemetry_hz is not None


class EscTelemetry:
    """The ESCs of one flight: ``due(sim_ns)`` says whether an epoch is due at this physics
    step; ``write(buf, offset, seq0, sim_ns, dt_s)`` writes its MOTORS records."""

    def __init__(self, cfg, physics_hz: int, ambient_c: float, omega_nodes, torque_nodes):
        rate = float(cfg.telemetry_hz)
        if not rate > 0.0:      # the schema refuses it too; a direct caller gets the same words
            raise ScenarioError(f"esc.telemetry_hz must be > 0 Hz, got {rate:g}")
        if rate > physics_hz:
            raise ScenarioError(f"esc.telemetry_hz = {rate:g} Hz is above the physics rate "
                                f"{physics_hz} Hz: reports are made once per physics step "
                                "at most; lower it or raise physics.rate_hz")
        self.schedule = Schedule(rate)
        self.period_s = 1.0 / rate
        self._omega = list(omega_nodes)
        self._torque = list(torque_nodes)
        kv_rad = cfg.kv_rpm_v / _RPM_PER_RAD_S          # rad/s per volt
        self._ke = 1.0 / kv_rad                          # V s/rad = N m/A (Kt)
        self._r_ohm = float(cfg.winding_ohm)
        self._cells = int(cfg.battery_cells)
        self._capacity_mah = float(cfg.battery_mah)
        self._pack_ohm = cfg.battery_mohm * 1e-3
        self._avionics_a = float(cfg.avionics_a)
        self._k_per_w = float(cfg.temp_k_per_w)
        self._tau_s = float(cfg.temp_tau_s)
        self._ambient_c = float(ambient_c)
        self.temp_c = [self._ambient_c] * MOTORS
        self.mah = [0.0] * MOTORS
        self.avionics_mah = 0.0
        self.current_a = [0.0] * MOTORS
        self.rpm = [0.0] * MOTORS
        self.voltage_v = self._open_circuit_v()
        self.epochs = 0

    def due(self, sim_ns: int) -> bool:
        return sim_ns >= self.schedule.next_ns

    def _open_circuit_v(self) -> float:
        used = sum(self.mah) + self.avionics_mah
        cap = self._capacity_mah
        soc = 1.0 if cap <= 0 else min(1.0, max(0.0, 1.0 - used / cap))
        return self._cells * (_CELL_EMPTY_V + (_CELL_FULL_V - _CELL_EMPTY_V) * soc)

    def _pack_voltage(self, power_w: float) -> float:
        """Terminal voltage V with V = E - R (P / V + I_avionics): the larger root."""
        e = self._open_circuit_v() - self._pack_ohm * self._avionics_a
        disc = e * e - 4.0 * self._pack_ohm * power_w
        if disc <= 0.0:         # more power than the pack can give: it collapses to half
            return max(0.0, e / 2.0)
        return 0.5 * (e + math.sqrt(disc))

    def update(self) -> None:
        """Advance the electrical and thermal state by one report period (the values the
        ESCs report at this epoch)."""
        omega = [max(0.0, h.get_double_value()) for h in self._omega]
        q_nm = [max(0.0, h.get_double_value() * _LBFFT_NM) for h in self._torque]
        p_in = []
        for w, q in zip(omega, q_nm):
            i_m = q / self._ke
            v_m = w * self._ke + i_m * self._r_ohm
            p_in.append(v_m * i_m)
        v = self._pack_voltage(sum(p_in))
        dt = self.period_s
        decay = 1.0 - math.exp(-dt / self._tau_s)
        for m in range(MOTORS):
            i = p_in[m] / v if v > 0.0 else 0.0
            self.current_a[m] = i
            self.mah[m] += i * dt * _MAH_PER_AS
            target = self._ambient_c + self._k_per_w * p_in[m]
            self.temp_c[m] += (target - self.temp_c[m]) * decay
        self.avionics_mah += self._avionics_a * dt * _MAH_PER_AS
        self.voltage_v = v
        self.rpm = [w * _RPM_PER_RAD_S for w in omega]

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
