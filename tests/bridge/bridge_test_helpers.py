"""Shared helpers of the bridge tests: quiet-sensor overrides and record filters."""

from __future__ import annotations

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
