"""Scripted disturbances: external force, gyro bias, motor thrust bias, wind and turbulence.

Each [[disturbance]] of the scenario switches on before the first physics step
that starts at or after start_s and off before the first step that starts at
or after stop_s (default: never). While on:
- force: F(t) = m g A sin(2 pi f (t - t_on) + phase) along a unit axis in NED
  or body FRD, at the CG (f = 0: constant m g A). Forces in one frame add up;
  the bridge writes the summed vector into the JSBSim external force's
  direction with a 1 N magnitude (JSBSim does not renormalise runtime
  directions), so any number of them costs three property writes per step,
  done by the step kernel before each physics step.
- gyro_bias: sign * A * axis added to the IMU's gyro, as a step or a linear
  ramp over ramp_s; active biases add up.
- motor_bias: per-motor thrust (and reaction torque) scale; active biases multiply.
- wind: steady wind (speed, from-direction) plus optional JSBSim Dryden or
  Tustin turbulence (MIL-F-8785C severity); the last one switched on wins.
Every switch reports (sim_ns, text) to the simulator's event list.
"""

from __future__ import annotations

import math

from silbridge.bridge.fdm import G0_M_S2
from silbridge.bridge.frames import wind_from_to_ned

_TWO_PI = 2.0 * math.pi


def step_starting_at(t_s: float, dt_ns: int) -> int:
    """Index k of the first physics step whose start time (k-1) dt is >= t_s."""
    t_ns = int(round(t_s * 1e9))
    return -(-t_ns // dt_ns) + 1


class Disturbances:
    def __init__(self, scenario, fdm, imu, dt_ns: int, on_event):
        self.fdm = fdm
        self.imu = imu
        self.dt_ns = dt_ns
        self.mass_kg = fdm.mass_kg
        self.on_event = on_event     # on_event(sim_ns, text)
        switches = []
        for i, d in enumerate(scenario.disturbances):
            switches.append((step_starting_at(d.start_s, dt_ns), 1, i, d))
            if d.stop_s is not None and d.stop_s < scenario.duration_s:
                switches.append((step_starting_at(d.stop_s, dt_ns), 0, i, d))
        # Off before on at the same step, then in file order: deterministic.
        self._switches = sorted(switches, key=lambda s: (s[0], s[1], s[2]))
        self._next = 0
        self.next_step = self._switches[0][0] if self._switches else -1
        self._active: dict[int, tuple] = {}   # index -> (d, t_on_s)
        self.ramping = False   # a gyro bias ramps: update(k) every step until it ends
        self._force_plan: list = []
        self._force_frames: set = set()
        self.kernel = None   # attach_kernel(): the simulator's step kernel
        self._fault_scale = [1.0, 1.0, 1.0, 1.0]   # motor faults' (bridge/faults/motors.py)
        # Fixed 1 N magnitude; the summed force vector (N) goes into the direction.
        for frame in ("ned", "frd"):
            self.fdm.set_dist_force(frame, 1.0, (0.0, 0.0, 0.0))

    def switch(self, k: int) -> None:
        """Apply the switches due before step k (call when k == next_step)."""
        t_s = (k - 1) * self.dt_ns * 1e-9
        sim_ns = (k - 1) * self.dt_ns
        while self._next < len(self._switches) and self._switches[self._next][0] == k:
            _, on, i, d = self._switches[self._next]
            self._next += 1
            if on:
                self._active[i] = (d, t_s)
            else:
                self._active.pop(i, None)
            self.on_event(sim_ns, f"disturbance[{i}] {d.type} {'on' if on else 'off'}: {describe(d)}")
            if d.type == "motor_bias":
                self._apply_motor_bias()
            elif d.type == "wind":
                self._apply_wind(i if on else None)
        self.next_step = (self._switches[self._next][0] if self._next < len(self._switches) else -1)
        self._plan()
        self.ramping = any(d.type == "gyro_bias" for d, _ in self._active.values())
        for frame in ("ned", "frd"):
            if frame not in self._force_frames:
                self.fdm.set_dist_force(frame, 1.0, (0.0, 0.0, 0.0))
        # The step kernel writes the active forces before every run() from now on.
        self.kernel.set_forces(self._force_plan)
        self._update_gyro((k - 1) * self.dt_ns * 1e-9)

    def attach_kernel(self, kernel) -> None:
        """The simulator's step kernel, which writes the active forces before each physics
        step (bridge/src/step_forces.c set_forces)."""
        self.kernel = kernel
        kernel.set_forces(self._force_plan)

    def _plan(self) -> None:
        """The per-step work of the active forces (the hot path of S3) for the kernel: per
        frame, the direction setters and (m g A, 2 pi f, t_on, phase, periodic, axis)."""
        by_frame: dict[str, list] = {}
        for d, t_on in self._active.values():
            if d.type == "force":
                periodic = d.frequency_hz > 0
                by_frame.setdefault(d.frame, []).append(
                    (self.mass_kg * G0_M_S2 * d.amplitude_g, _TWO_PI * d.frequency_hz, t_on,
                     math.radians(d.phase_deg), periodic, tuple(float(a) for a in d.axis)))
        handles = {"ned": self.fdm.h_dist_ned, "frd": self.fdm.h_dist_frd}
        self._force_plan = [(tuple(h.set_double_value for h in handles[f][1:]), items)
                            for f, items in by_frame.items()]
        self._force_frames = set(by_frame)

    def update(self, k: int) -> None:
        """Per step while a gyro bias ramps (forces are the kernel's)."""
        if self.ramping:
            self._update_gyro((k - 1) * self.dt_ns * 1e-9)

    def _update_gyro(self, t_s: float) -> None:
        gyro = [0.0, 0.0, 0.0]
        ramping = False
        for d, t_on in self._active.values():
            if d.type != "gyro_bias":
                continue
            frac = 1.0
            if d.ramp_s > 0:
                frac = min(1.0, (t_s - t_on) / d.ramp_s)
                ramping = ramping or frac < 1.0
            a = d.sign * d.amplitude_rad_s * frac
            for j in range(3):
                gyro[j] += a * d.axis[j]
        self.imu.set_injected_gyro_bias(gyro)
        self.ramping = ramping

    def set_fault_thrust_scale(self, scale) -> None:
        """The motor faults' thrust scales (issue 28), times the active motor biases."""
        self._fault_scale = [float(s) for s in scale]
        self._apply_motor_bias()

    def _apply_motor_bias(self) -> None:
        scale = list(self._fault_scale)
        for d, _ in self._active.values():
            if d.type == "motor_bias":
                scale = [a * b for a, b in zip(scale, d.thrust_scale)]
        for i, s in enumerate(scale):
            self.fdm.set_thrust_scale(i, s)

    def _apply_wind(self, index_on) -> None:
        winds = [(i, d) for i, (d, _) in self._active.items() if d.type == "wind"]
        if not winds:
            self.fdm.set_wind_ned((0.0, 0.0, 0.0))
            self.fdm.set_turbulence("none", 0.0, 1)
            return
        d = dict(winds)[index_on] if index_on is not None else winds[-1][1]
        self.fdm.set_wind_ned(wind_from_to_ned(d.speed_m_s, d.from_deg))
        self.fdm.set_turbulence(d.turbulence, d.speed_m_s, d.severity)


def describe(d) -> str:
    if d.type == "force":
        return (f"{d.amplitude_g:.3f} g at {d.frequency_hz:.3f} Hz along "
                f"[{d.axis[0]:.2f}, {d.axis[1]:.2f}, {d.axis[2]:.2f}] {d.frame}")
    if d.type == "gyro_bias":
        return (f"{d.sign * d.amplitude_rad_s:+.4f} rad/s along "
                f"[{d.axis[0]:.2f}, {d.axis[1]:.2f}, {d.axis[2]:.2f}] frd"
                + (f", ramp {d.ramp_s:.2f} s" if d.ramp_s > 0 else ", step"))
    if d.type == "motor_bias":
        return "thrust scale " + ", ".join(f"{s:.3f}" for s in d.thrust_scale)
    return (f"wind {d.speed_m_s:.2f} m/s from {d.from_deg:.0f} deg, turbulence {d.turbulence}"
            + (f" severity {d.severity}" if d.turbulence != "none" else ""))

