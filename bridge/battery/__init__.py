"""The physics-side battery: one pack every autopilot reads (issue 28).

The pack runs inside the bridge's C step kernel (bridge/src/battery.h documents the model
and its sources; the formulas' readable reference is tests/bridge/battery_reference.py):
every ``1 / rate_hz`` of sim time ([battery] rate_hz, 10 Hz: ArduCopter reads its battery
monitor at 10 Hz) the step advances the pack over the period under the ESCs' input power
(load.py) plus the avionics current, and writes one BATTERY record (shm/records.py),
quantised at the source to what MAVLink's BATTERY_STATUS carries (whole mV per cell,
0.01 A, whole mAh, whole %, 0.01 degC) so that shared memory and HIL agree. A report needs
no Python, so it does not end a lockstep batch (issue 25).

Python keeps what is not per step: ``Battery`` turns the scenario's [battery] and [esc]
keys into the kernel's configuration, its ``applier`` (faults.py) switches the battery
faults through the kernel, and its properties read the pack's state at its last report
(the mag's motor interference, the run summary). ``load`` and ``solve`` serve the ESC
telemetry (bridge/esc_telemetry.py), which reads the same pack.
"""

from __future__ import annotations

from silbridge.bridge.battery.faults import BatteryFaults
from silbridge.bridge.battery.load import MotorLoad

__all__ = ["Battery", "BatteryFaults", "MotorLoad"]


class Battery:
    """The pack of one flight, configured from the scenario and run by the kernel bound
    with ``attach``. Read voltage_v, current_a, consumed_mah, remaining (0..1),
    temperature_c, lowest_cell_v, reports: the pack's state at its last report."""

    def __init__(self, cfg, air_c: float, esc_cfg):
        self.cfg = cfg
        self.air_c = float(air_c)
        self.esc_cfg = esc_cfg
        self.kernel = None
        self.load = None
        self.applier = BatteryFaults(self)

    def attach(self, kernel, omega_nodes, torque_nodes) -> None:
        """Configure the kernel's pack; omega_nodes and torque_nodes: JSBSim's
        fcs/mN-omega-rad_s and fcs/mN-torque-lbsft property nodes, motors 1..4."""
        c, esc = self.cfg, self.esc_cfg
        self.load = MotorLoad(esc, omega_nodes, kernel)
        kernel.configure_battery(
            torque=[n.get_double_value for n in torque_nodes], cells=int(c.cells),
            capacity_mah=float(c.capacity_mah), internal_mohm=float(c.internal_mohm),
            avionics_a=float(c.avionics_a), initial_soc=float(c.initial_soc),
            temperature_c=self.air_c if c.temperature_c is None else float(c.temperature_c),
            air_c=self.air_c, activation_kj_mol=float(c.activation_kj_mol),
            heat_capacity_j_k=float(c.heat_capacity_j_k),
            thermal_k_per_w=float(c.thermal_k_per_w), rate_hz=float(c.rate_hz),
            ke_v_s_rad=self.load.ke, winding_ohm=self.load.r_ohm)
        self.kernel = kernel

    def _state(self, i: int):
        return self.kernel.battery_state()[i]

    voltage_v = property(lambda self: self._state(0))
    current_a = property(lambda self: self._state(1))
    consumed_mah = property(lambda self: self._state(2))
    remaining = property(lambda self: self._state(3))
    temperature_c = property(lambda self: self._state(4))
    lowest_cell_v = property(lambda self: self._state(5))
    reports = property(lambda self: self._state(6))
    next_ns = property(lambda self: self._state(7))     # sim time of the next report

    def solve(self, esc_power_w: float) -> tuple:
        """(terminal voltage [V], pack current [A]) under the ESCs' total input power now,
        without advancing the pack."""
        return self.kernel.battery_solve(esc_power_w)
