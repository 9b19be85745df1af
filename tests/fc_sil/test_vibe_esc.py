"""VIBRATION and ESC telemetry in the C core, through the record batches the FC runs on.

The vibration levels are held against a slow Python oracle of ArduPilot's
AP_InertialSensor::calc_vibration_and_clipping (5 Hz floor low-pass, (a - floor)^2 through a
2 Hz low-pass, sqrt; DigitalLPF starts at its first sample), the clip count against the samples
beyond (16 - 0.5) g. ESC records are stored per motor and change nothing the controller does.
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import records as R

G = 9.80665
DT_S = 1e-3
CLIP_M_S2 = 15.5 * G


def _imu_records(accel_rows) -> np.ndarray:
    n = len(accel_rows)
    r = R.empty(R.Kind.IMU, n)
    r["seq"] = np.arange(n)
    r["sim_ns"] = (np.arange(n) + 1) * 1_000_000
    r["accel_frd_m_s2"] = accel_rows
    return R.as_generic(r)


def _esc_records(sim_ns: int, rows, seq0: int = 0) -> np.ndarray:
    r = R.empty(R.Kind.ESC, len(rows))
    for i, (motor, rpm, v, a, t, mah) in enumerate(rows):
        r[i]["seq"] = seq0 + i
        r[i]["sim_ns"] = sim_ns
        r[i]["motor"], r[i]["motor_count"] = motor, len(rows)
        r[i]["rpm"], r[i]["voltage_v"], r[i]["current_a"] = rpm, v, a
        r[i]["temperature_c"], r[i]["consumption_mah"] = t, mah
    return R.as_generic(r)


def _oracle(accel_rows, dt_s: float):
    """ArduPilot's vibration levels and clip count of these samples (float64)."""
    def alpha(fc):
        return dt_s / (dt_s + 1.0 / (2.0 * math.pi * fc))
    floor, vibe, clips = None, [0.0] * 3, 0
    for a in accel_rows:
        if any(abs(x) > CLIP_M_S2 for x in a):
            clips += 1
        if floor is None:
            floor = list(a)
            continue
        for i in range(3):
            floor[i] += (a[i] - floor[i]) * alpha(5.0)
            d = a[i] - floor[i]
            vibe[i] += (d * d - vibe[i]) * alpha(2.0)
    return [math.sqrt(v) for v in vibe], clips


def _shaken(amp_m_s2: float, freq_hz: float, seconds: float) -> np.ndarray:
    t = np.arange(int(seconds / DT_S)) * DT_S
    a = np.zeros((len(t), 3), dtype=np.float32)
    a[:, 0] = 0.3 * amp_m_s2 * np.sin(2 * np.pi * freq_hz * t)
    a[:, 1] = 0.6 * amp_m_s2 * np.sin(2 * np.pi * freq_hz * t + 1.0)
    a[:, 2] = -G + amp_m_s2 * np.sin(2 * np.pi * 2 * freq_hz * t)
    return a


def test_vibration_levels_follow_ardupilots_filters_and_grow_with_the_shaking():
    levels = []
    for amp in (1.0, 4.0):
        acc = _shaken(amp, 80.0, 3.0)
        core = FlightCore()
        core.step_batch(_imu_records(acc))
        x, y, z, clips = core.vibration()
        want, want_clips = _oracle(acc.astype(np.float64).tolist(), DT_S)
        np.testing.assert_allclose([x, y, z], want, rtol=2e-3)
        assert clips == want_clips == 0
        levels.append((x, y, z))
    # A sine of amplitude A has RMS A / sqrt(2); four times the shaking, four times the level.
    assert levels[1][2] > 3.5 * levels[0][2]
    assert abs(levels[1][2] - 4.0 / math.sqrt(2.0)) < 0.15 * 4.0 / math.sqrt(2.0)


def test_clip_count_counts_samples_beyond_the_16g_range_less_half_a_g():
    acc = np.tile(np.array([[0.0, 0.0, -G]], dtype=np.float32), (1000, 1))
    acc[100:130, 2] = -156.9          # at the +-16 g range: clipped
    acc[200:205, 0] = 153.0           # just beyond 15.5 g on x
    acc[300:310, 1] = 150.0           # below 15.5 g: not a clip
    core = FlightCore()
    core.step_batch(_imu_records(acc))
    *_, clips = core.vibration()
    assert clips == 35 == _oracle(acc.astype(np.float64).tolist(), DT_S)[1]


def test_a_nan_sample_is_refused_and_leaves_the_levels_finite():
    acc = _shaken(2.0, 60.0, 1.0)
    acc[500, 1] = np.nan
    core = FlightCore()
    core.step_batch(_imu_records(acc))
    x, y, z, _ = core.vibration()
    assert all(math.isfinite(v) and v > 0 for v in (x, y, z))


def test_esc_reports_are_stored_per_motor():
    core = FlightCore()
    rows = [(m, 5000.0 + m, 16.47, 2.1 + m, 15.0, 19.0) for m in range(4)]
    core.step_batch(_esc_records(20_000_000, rows))
    core.step_batch(_esc_records(40_000_000, rows, seq0=4))
    reps = core.esc_reports()
    assert [r.motor for r in reps] == [0, 1, 2, 3]
    assert [r.rpm for r in reps] == [5000.0, 5001.0, 5002.0, 5003.0]
    assert all(r.count == 2 and r.sim_ns == 40_000_000 for r in reps)
    assert reps[3].current_a == np.float32(5.1)
    assert reps[0].voltage_v == np.float32(16.47)


def test_bad_esc_reports_are_refused():
    core = FlightCore()
    core.step_batch(_esc_records(1_000_000, [(9, 1.0, 16.0, 1.0, 20.0, 0.0)]))   # no motor 10
    core.step_batch(_esc_records(1_000_000, [(0, float("nan"), 16.0, 1.0, 20.0, 0.0)]))
    assert core.esc_reports() == []
    reports, rejected, _, _ = core._c.esc_reports()
    assert (reports, rejected) == (0, 2)


def test_esc_records_change_no_pwm(stream):
    """The same sensor batches with and without ESC reports give the same PWM and status."""
    out = []
    for with_esc in (False, True):
        s = stream(imu_hz=1000.0)
        core = FlightCore()
        core.arm()
        core.set_throttle(0.5)
        pwm_all = []
        for k in range(20):
            recs = s.batch(50)
            if with_esc:
                esc = _esc_records(int(recs["sim_ns"][-1]), [(m, 4000.0, 16.0, 2.0, 20.0, k)
                                                             for m in range(4)], seq0=4 * k)
                recs = np.concatenate([recs, esc])
            pwm, status = core.step_batch(recs)
            pwm_all.append((pwm["pwm_us"].copy(), status.tobytes()))
        out.append(pwm_all)
    for (p0, s0), (p1, s1) in zip(*out):
        assert np.array_equal(p0, p1) and s0 == s1
