"""Prop wash (bridge/src/vibration.h): broadband thrust fluctuation of each rotor, off by
default (real JSBSim, the C sensor stage). Its RMS grows with the rotor's thrust; the
accelerometer and the gyro read one motion; the same seed gives the same bytes."""

import hashlib
import math

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from bridge_test_helpers import QUIET_IMU, of_kind

DT_S = 1e-3
# The wash alone: the rotor lines off, the IMU's own noise off.
ONLY_WASH = {**QUIET_IMU, "vibration.enabled": True, "vibration.imbalance_g_mm": 0.0,
             "vibration.blade_pass_ripple": 0.0, "vibration.harmonic_ripple": [0.0] * 4,
             "vibration.prop_wash": 0.02}


def spin(overrides, pwm_below_hover_us, steps=3000, seed=None):
    """All IMU records and the rotor speed at the end, on the ground at a constant PWM."""
    sim = Simulator(load_scenario("S1", seed=seed, overrides=overrides))
    pwm = (sim.hover_pwm_us - pwm_below_hover_us,) * 4
    recs = np.concatenate([sim.step(pwm).copy() for _ in range(steps)])
    return of_kind(recs, Kind.IMU), sim.rotor_rad_s()[0]


def test_prop_wash_is_off_by_default():
    assert load_scenario("V1").vibration.prop_wash == 0.0
    assert load_scenario("V2").vibration.prop_wash == 0.0


def test_prop_wash_rms_grows_as_the_rotors_thrust():
    """The same draws (same seed) at two throttles: the RMS ratio is the thrust ratio."""
    low, w_low = spin(ONLY_WASH, 250.0)
    high, w_high = spin(ONLY_WASH, 60.0)
    thrust_ratio = (w_high / w_low) ** 2
    assert thrust_ratio > 1.8
    for field, axes in (("accel_frd_m_s2", (0, 1, 2)), ("gyro_frd_rad_s", (0, 1))):
        rms_low = low[field][1000:].astype(float).std(axis=0)
        rms_high = high[field][1000:].astype(float).std(axis=0)
        for a in axes:
            assert rms_low[a] > 0.0
            assert rms_high[a] / rms_low[a] == pytest.approx(thrust_ratio, rel=0.02), (field, a)
    # broadband: no line, the power spreads over the band (the largest bin holds < 2 %)
    z = high["accel_frd_m_s2"][1000:, 2].astype(float)
    power = np.abs(np.fft.rfft(z - z.mean())) ** 2
    assert power.max() < 0.02 * power.sum()


def test_accel_and_gyro_read_one_motion_with_prop_wash():
    """Two IMU places on a hard mount: the accelerometers differ by alpha x dr, alpha the
    change of the gyro's reading over the step (float32 records: a small tolerance)."""
    dr = np.array((0.08, -0.05, -0.04))
    base = {**ONLY_WASH, "mount.type": "hard"}
    imu0, _ = spin({**base, "mount.imu_offset_frd_m": [0.0, 0.0, 0.0]}, 60.0, steps=1500)
    imu1, _ = spin({**base, "mount.imu_offset_frd_m": dr.tolist()}, 60.0, steps=1500)
    g = imu0["gyro_frd_rad_s"].astype(float)
    assert np.array_equal(imu0["gyro_frd_rad_s"], imu1["gyro_frd_rad_s"])
    alpha = np.diff(g, axis=0) / DT_S
    d_acc = (imu1["accel_frd_m_s2"].astype(float) - imu0["accel_frd_m_s2"].astype(float))[1:]
    predicted = np.cross(alpha, dr)
    tail = slice(500, None)
    scale = np.abs(predicted[tail]).max()
    assert scale > 0.05                                      # m/s^2: the lever arm shows
    assert np.abs(d_acc[tail] - predicted[tail]).max() < 0.01 * scale


def _hash(seed, wash):
    sim = Simulator(load_scenario("V2", seed=seed, overrides={"vibration.prop_wash": wash}))
    h = hashlib.md5()
    pwm = (sim.hover_pwm_us + 40.0,) * 4
    for _ in range(1500):
        h.update(sim.step(pwm).tobytes())
    return h.hexdigest()


def test_same_seed_same_bytes_with_prop_wash_on():
    assert _hash(3, 0.02) == _hash(3, 0.02)
    assert _hash(3, 0.02) != _hash(4, 0.02)
    assert _hash(3, 0.02) != _hash(3, 0.0)                   # it is there


def test_the_lines_are_untouched_by_prop_wash_off():
    """prop_wash = 0 runs no wash code: V2's bytes equal those of the scenario as written."""
    sim_a = Simulator(load_scenario("V2", seed=3))
    sim_b = Simulator(load_scenario("V2", seed=3, overrides={"vibration.prop_wash": 0.0}))
    pwm = (sim_a.hover_pwm_us,) * 4
    for _ in range(500):
        assert sim_a.step(pwm).tobytes() == sim_b.step(pwm).tobytes()
    assert math.isfinite(sim_a.rotor_rad_s()[0])
