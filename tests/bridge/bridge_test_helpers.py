"""Shared helpers of the bridge tests: quiet-sensor overrides, record filters and a
flight profile that exercises the step kernel."""

from __future__ import annotations

import hashlib
import math

import numpy as np

from silbridge.shm.records import DTYPES, Kind

# Every sensor error source off: the sensors must then read the truth exactly.
QUIET_IMU = {
    "imu.gyro_noise_density": 0.0, "imu.accel_noise_density": 0.0,
    "imu.gyro_bias_walk": 0.0, "imu.accel_bias_walk": 0.0,
    "imu.gyro_turn_on_bias": 0.0, "imu.accel_turn_on_bias": 0.0,
    "imu.gyro_tempco": 0.0, "imu.accel_tempco": 0.0,
    "imu.vib_accel": 0.0, "imu.vib_gyro": 0.0,
}
QUIET_LOWRATE = {
    "baro.noise_pa": 0.0, "baro.lag_s": 0.0, "mag.noise_gauss": 0.0,
    "gnss.pos_sigma_h_m": 0.0, "gnss.pos_sigma_v_m": 0.0, "gnss.vel_sigma_m_s": 0.0,
}


def of_kind(recs: np.ndarray, kind: Kind) -> np.ndarray:
    return recs[recs["kind"] == int(kind)].view(DTYPES[kind])


def collect(sim, pwm, steps: int) -> np.ndarray:
    """Run `steps` steps with a constant PWM; return all records (copied)."""
    out = [sim.step(pwm).copy() for _ in range(steps)]
    return np.concatenate(out)


def take_off_and_flip(sim, k: int) -> tuple[float, float, float, float]:
    """PWM of step k: ground idle, a wobbly climb (a new width most steps), then an
    asymmetric push that tips the quad over."""
    h = sim.hover_pwm_us
    if k < 300:
        return (1000.0, 1000.0, 1000.0, 1000.0)
    if k < 2500:
        w = 40.0 * math.sin(k / 37.0)
        return (h + 120 + w, h + 120 - w, h + 118 + 0.5 * w, h + 121 - 0.5 * w)
    return (h + 300, h - 300, h + 300, h - 300)     # a hard roll/pitch: flips, then falls


def profile_digest(sim, steps: int) -> str:
    """SHA-256 of every record of `steps` steps of take_off_and_flip."""
    digest = hashlib.sha256()
    for k in range(steps):
        digest.update(sim.step(take_off_and_flip(sim, k)).tobytes())
    return digest.hexdigest()
