"""The bridge's own fault appliers, registered with the simulator's fault engine once its
kernel exists (Simulator._attach_kernel). battery (H2's physics-side battery) and link (the
SIL link) register themselves where they live; rc and gcs are the FC's."""

from __future__ import annotations

from silbridge.bridge.faults.gnss import GnssApplier
from silbridge.bridge.faults.motors import MotorApplier
from silbridge.bridge.faults.sensors import BaroApplier, InertialApplier, MagApplier, NoiseSeed


def register_all(sim) -> None:
    engine, kernel = sim.faults, sim.kernel
    noise_seed = NoiseSeed(kernel, sim.scenario.seed)
    one_per_step = sim.imu_hz == sim.physics_hz
    engine.register("gnss", GnssApplier(engine, sim.gnss))
    engine.register("baro", BaroApplier(engine, kernel))
    engine.register("mag", MagApplier(engine, kernel, sim))
    engine.register("gyro", InertialApplier(engine, kernel, "gyro", noise_seed, one_per_step))
    engine.register("accel", InertialApplier(engine, kernel, "accel", noise_seed, one_per_step))
    engine.register("motor", MotorApplier(engine, sim))
