"""The electrical load the motors put on the pack, from JSBSim's motor model.

The DC-motor equivalent of the 2212 920KV motor of jsbsim_models/quadx/motors.xml (KV and
winding resistance are the [esc] keys, derivations in bridge/scenario_schema.py): the
model's shaft torque ``fcs/mN-torque-lbsft`` needs the motor current I_m = Q / Kt,
Kt = 60 / (2 pi KV) N m/A; the winding needs V_m = omega / KV + I_m R. Each ESC, a lossless
buck converter here, draws P = V_m I_m from the pack, so its battery-side current is
P / V_pack. No-load (iron and friction) current is neglected. The step kernel computes it
(bridge/src/battery.c sb_pack_esc_power); this class gives its constants and serves the
ESC telemetry.
"""

from __future__ import annotations

import math

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


class MotorLoad:
    """``omega_rad_s()`` reads the rotors' speed from JSBSim property nodes; ``power_w()`` is
    each ESC's input power now [W], motor order, computed by the kernel's pack."""

    def __init__(self, esc_cfg, omega_nodes, kernel):
        self._omega = list(omega_nodes)
        self._kernel = kernel
        self.ke = RPM_PER_RAD_S / esc_cfg.kv_rpm_v       # V s/rad = N m/A (Kt)
        self.r_ohm = float(esc_cfg.winding_ohm)

    def omega_rad_s(self) -> list:
        return [max(0.0, h.get_double_value()) for h in self._omega]

    def power_w(self, omega=None) -> list:
        omega = self.omega_rad_s() if omega is None else omega
        return list(self._kernel.battery_esc_power(tuple(omega)))
