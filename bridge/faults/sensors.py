"""Gyro, accelerometer, barometer and magnetometer faults: each applier folds its unit's
active faults into the C sensor stage's fault set (bridge/src/sensor_faults.h) through the
Kernel's set_*_fault methods whenever the engine switches one. Nothing here runs per step.

- gyro, accel (instance 0 or 1: the one IMU): stuck axes repeat the first sample under the
  fault; bias steps add; noisy axes add white noise of sigma (a seeded generator in C, its
  seed from the run's named stream "fault:imu_noise"; two noisy faults on an axis add in
  quadrature); clip saturates at the smallest active limit. The one-per-step IMU sample only
  (imu.rate_hz = physics.rate_hz; the scenario check says so).
- baro: glitch offsets and drifts are altitude errors, turned into pressure in C at the
  local air density; stuck repeats the first reading under the fault.
- mag: off silences it (no MAG records; its schedule and noise run on); motor_interference
  adds gauss_per_a x the battery current (sim.battery.current_a, the physics-side battery)
  to the hard-iron offset, refreshed on the steps Python sees (at least every GNSS epoch).
"""

from __future__ import annotations

import math

from silbridge.bridge.faults.engine import FaultError
from silbridge.bridge.scenario import draw_rng


def _axes(axis: int) -> tuple:
    """The catalog's axis parameter: 0 every axis, 1 x, 2 y, 3 z."""
    return (0, 1, 2) if axis == 0 else (axis - 1,)


class NoiseSeed:
    """The C generator of the noisy-axis faults (one for gyro and accel), seeded from the
    run's named stream "fault:imu_noise" when a noisy fault first needs it."""

    def __init__(self, kernel, seed: int):
        self.kernel, self.seed, self.done = kernel, seed, False

    def ensure(self) -> None:
        if not self.done:
            self.done = True
            self.kernel.set_fault_seed(int(draw_rng(self.seed, "fault:imu_noise")
                                           .integers(0, 2**63)))


class InertialApplier:
    """unit: "gyro" or "accel"; noise_seed: the NoiseSeed both share; one_per_step: the
    kernel writes one IMU sample per step (the only IMU these faults reach)."""

    def __init__(self, engine, kernel, unit: str, noise_seed: NoiseSeed, one_per_step: bool):
        self.engine, self.kernel, self.unit = engine, kernel, unit
        self.noise_seed = noise_seed
        self.one_per_step = one_per_step

    def on(self, fault, sim_ns: int) -> None:
        if not self.one_per_step:
            raise FaultError(f"{self.unit} faults act on the one-per-step IMU sample: run "
                             f"with imu.rate_hz = physics.rate_hz")
        stuck, bias, var, clip = [False] * 3, [0.0] * 3, [0.0] * 3, -1.0
        for f in self.engine.active(self.unit):
            p = f.params
            if f.type == "stuck":
                for i in _axes(p["axis"]):
                    stuck[i] = True
            elif f.type == "bias":
                bias = [b + x for b, x in zip(bias, p["bias"])]
            elif f.type == "noisy":
                for i in _axes(p["axis"]):
                    var[i] += p["sigma"] ** 2
            elif f.type == "clip":
                clip = p["limit"] if clip < 0 else min(clip, p["limit"])
        if any(var):
            self.noise_seed.ensure()
        self.kernel.set_imu_fault(sensor=self.unit, stuck=tuple(stuck), bias=tuple(bias),
                                  sigma=tuple(math.sqrt(v) for v in var), clip=clip)

    off = on


class BaroApplier:
    def __init__(self, engine, kernel):
        self.engine, self.kernel = engine, kernel

    def on(self, fault, sim_ns: int) -> None:
        stuck, offset_m, drift_m_s = False, 0.0, 0.0
        for f in self.engine.active("baro"):
            if f.type == "stuck":
                stuck = True
            elif f.type == "glitch":
                offset_m += f.params["offset_m"]
            elif f.type == "drift":   # rate (t - t_on): the line's value at t = 0 is -rate t_on
                rate = f.params["rate_m_s"]
                drift_m_s += rate
                offset_m -= rate * f.t_on_ns * 1e-9
        self.kernel.set_baro_fault(stuck=stuck, offset_m=offset_m, drift_m_s=drift_m_s)

    off = on


class MagApplier:
    """sim: the Simulator (its scenario's hard-iron offset, its battery's current)."""

    def __init__(self, engine, kernel, sim):
        self.engine, self.kernel, self.sim = engine, kernel, sim
        self.offset_gauss = tuple(sim.scenario.mag.offset_gauss)
        self.gauss_per_a = (0.0, 0.0, 0.0)
        self.current_a = 0.0

    def on(self, fault, sim_ns: int) -> None:
        gpa = [0.0, 0.0, 0.0]
        for f in self.engine.active("mag"):
            if f.type == "motor_interference":
                gpa = [g + x for g, x in zip(gpa, f.params["gauss_per_a"])]
        self.gauss_per_a = tuple(gpa)
        interfering = any(gpa)
        if interfering and getattr(self.sim, "battery", None) is None:
            raise FaultError("mag motor_interference follows the battery current: this run "
                             "has no physics-side battery (sim.battery)")
        self.engine.set_poll(self, interfering)
        self.current_a = self.sim.battery.current_a if interfering else 0.0
        self._write()

    off = on

    def poll(self, sim_ns: int) -> None:
        """On the steps Python sees: follow the battery current."""
        current = self.sim.battery.current_a
        if current != self.current_a:
            self.current_a = current
            self._write()

    def _write(self) -> None:
        off = any(f.type == "off" for f in self.engine.active("mag"))
        offset = tuple(o + g * self.current_a for o, g in zip(self.offset_gauss, self.gauss_per_a))
        self.kernel.set_mag_fault(off=off, offset_gauss=offset)
