"""fc_mahony.c: attitude estimator (paper Listing 3, corrected).

Synthetic IMU data of a vehicle at rest or rotating at a known rate, fed to
the real C estimator at 1 kHz.
"""

import numpy as np
import pytest

import fc_blocks as B

DT = 0.001
G = 9.80665


def quat_from_euler(roll, pitch, yaw):
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.array([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def rot(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def angle_between(q1, q2):
    d = abs(float(np.dot(q1, q2)))
    return 2 * np.arccos(min(1.0, d))


def tilt_error(q1, q2):
    """Angle between the gravity directions of two attitudes (yaw is not
    observable from the accelerometer, so tilt convergence ignores it)."""
    d1, d2 = rot(q1)[2], rot(q2)[2]
    return np.arccos(np.clip(np.dot(d1, d2), -1.0, 1.0))


def at_rest(q_true, n, gyro_bias=(0.0, 0.0, 0.0)):
    f_frd = rot(q_true).T @ np.array([0.0, 0.0, -G])
    return np.tile(gyro_bias, (n, 1)), np.tile(f_frd, (n, 1))


def test_converges_from_30_degrees_off():
    q_true = quat_from_euler(0.1, -0.05, 0.0)
    m = B.Mahony()
    m.set_attitude(quat_from_euler(0.1 + np.radians(30), -0.05, 0.0))
    gyro, acc = at_rest(q_true, 60_000)
    q, _, trust = m.run(gyro, acc, DT)
    err = np.degrees([tilt_error(q[i], q_true) for i in (0, 5000, 29_999, 59_999)])
    assert err[0] > 29
    assert err[1] < 3          # well on its way after 5 s
    assert err[2] < 0.25       # the PI's slow pole (7 s at kp 0.5, ki 0.05) after 30 s
    assert err[3] < 0.02       # converged after 60 s
    assert np.all(np.diff(err) < 0)
    assert trust[-1] == pytest.approx(1.0, abs=1e-3)


def test_tracks_an_injected_gyro_bias():
    bias = np.array([0.05, -0.05, 0.0])
    q_true = quat_from_euler(0.0, 0.0, 0.0)
    m = B.Mahony()
    m.set_attitude(q_true)
    gyro, acc = at_rest(q_true, 120_000, bias)
    q, b, _ = m.run(gyro, acc, DT)
    np.testing.assert_allclose(b[-1, :2], bias[:2], atol=0.003)
    assert angle_between(q[-1], q_true) < np.radians(0.3)
    # Without bias estimation the PI integrator alone still holds the attitude.
    m2 = B.Mahony(bias=False)
    m2.set_attitude(q_true)
    q2, b2, _ = m2.run(gyro, acc, DT)
    assert np.all(b2[-1] == 0.0)
    assert angle_between(q2[-1], q_true) < np.radians(0.3)


def test_heading_from_magnetometer_makes_yaw_bias_observable():
    bias = np.array([0.0, 0.0, 0.05])
    q_true = quat_from_euler(0.0, 0.0, 0.7)
    field_ned = np.array([0.2, 0.0, 0.4])
    field_frd = rot(q_true).T @ field_ned
    m = B.Mahony()
    m.set_attitude(quat_from_euler(0.0, 0.0, 0.0))
    gyro, acc = at_rest(q_true, 10, bias)
    for _ in range(12_000):             # 120 s: IMU 1 kHz, magnetometer 100 Hz
        q, b, _ = m.run(gyro, acc, DT)
        assert m.mag(field_frd) == 0
    assert angle_between(q[-1], q_true) < np.radians(0.5)
    assert b[-1, 2] == pytest.approx(0.05, abs=0.005)


def test_first_magnetometer_sample_sets_the_heading_at_once():
    q_true = quat_from_euler(0.2, 0.1, -2.0)
    m = B.Mahony()
    m.set_attitude(quat_from_euler(0.2, 0.1, 0.0))
    assert m.mag(rot(q_true).T @ np.array([0.25, 0.0, 0.3])) == 0
    q = np.array(m.state()["q_wxyz"])
    assert angle_between(q, q_true) < np.radians(0.5)


def test_trust_follows_the_accelerometer_magnitude_through_an_ema():
    m = B.Mahony(trust_tc_s=0.2)
    gyro, acc = at_rest(np.array([1.0, 0, 0, 0]), 3000)
    acc[1000:] *= 1.5                               # |a| = 1.5 g: raw trust 0.5
    _, _, trust = m.run(gyro, acc, DT)
    # trust starts at 0 and rises with the EMA: 1 - exp(-t/tau)
    assert trust[199] == pytest.approx(1.0 - np.exp(-1), abs=0.01)
    assert trust[999] == pytest.approx(1.0 - np.exp(-5), abs=1e-3)
    # one time constant after the step: 63 % of the way towards 0.5
    t0 = trust[999]
    assert trust[1199] == pytest.approx(t0 + (0.5 - t0) * (1 - np.exp(-1)), abs=0.01)
    assert trust[-1] == pytest.approx(0.5, abs=1e-3)
    m_raw = B.Mahony(trust_ema=False)
    _, _, trust_raw = m_raw.run(gyro, acc, DT)
    assert trust_raw[1000] == pytest.approx(0.5, abs=1e-5)


def test_trust_is_per_estimator_not_shared():
    # The paper's listing kept trust in a function-local static; ours is state.
    a, b = B.Mahony(), B.Mahony()
    gyro, acc = at_rest(np.array([1.0, 0, 0, 0]), 500)
    a.run(gyro, acc, DT)
    assert b.state()["trust"] == 0.0
    assert a.state()["trust"] > 0.9


def test_integrates_rotation_exactly_without_correction():
    m = B.Mahony(kp=0.0, ki=0.0, bias=False)
    m.set_attitude([1, 0, 0, 0])
    gyro = np.tile([0.0, 0.0, 1.0], (1000, 1))      # 1 rad/s yaw for 1 s
    acc = np.tile([0.0, 0.0, -G], (1000, 1))
    q, _, _ = m.run(gyro, acc, DT)
    assert angle_between(q[-1], quat_from_euler(0, 0, 1.0)) < 1e-4
    assert np.linalg.norm(q[-1]) == pytest.approx(1.0, abs=1e-6)


def test_non_finite_input_leaves_the_state_unchanged():
    m = B.Mahony()
    gyro, acc = at_rest(np.array([1.0, 0, 0, 0]), 200)
    m.run(gyro, acc, DT)
    before = m.state()
    gyro[:, 0] = np.nan
    q, b, t = m.run(gyro, acc, DT)
    assert np.isfinite(q).all() and np.isfinite(b).all() and np.isfinite(t).all()
    assert m.state()["q_wxyz"] == before["q_wxyz"]


def test_trust_span_sets_where_the_raw_trust_reaches_zero():
    gyro, acc = at_rest(np.array([1.0, 0, 0, 0]), 10)
    _, _, t = B.Mahony(trust_ema=False, trust_span_g=0.25).run(gyro, acc * 1.1, DT)
    assert t[-1] == pytest.approx(1 - 0.1 / 0.25, abs=1e-4)
    _, _, t = B.Mahony(trust_ema=False).run(gyro, acc * 1.1, DT)
    assert t[-1] == pytest.approx(0.9, abs=1e-4)             # the listing's 1 g span


def test_acceleration_reference_holds_the_tilt_through_a_sustained_acceleration():
    # Rolled 20 deg, height held, no drag: the vehicle accelerates east at g tan(20)
    # and the accelerometer sees only the thrust axis. Gravity alone as the
    # reference pulls the estimate towards level; the kinematic reference does not.
    roll = np.radians(20)
    q_true = quat_from_euler(roll, 0.0, 0.0)
    f_frd = np.array([0.0, 0.0, -G / np.cos(roll)])
    a_ned = np.array([0.0, G * np.tan(roll), 0.0])
    gyro = np.zeros((100, 3))
    acc = np.tile(f_frd, (100, 1))
    plain, aided = B.Mahony(), B.Mahony()
    for m in (plain, aided):
        m.set_attitude(q_true)
    for _ in range(100):                         # 10 s; reference at 10 Hz
        q_plain, _, _ = plain.run(gyro, acc, DT)
        assert aided.set_accel_ref(a_ned) == 0
        q_aided, _, trust = aided.run(gyro, acc, DT)
    assert np.degrees(tilt_error(q_plain[-1], q_true)) > 10
    assert np.degrees(tilt_error(q_aided[-1], q_true)) < 0.1
    assert trust[-1] == pytest.approx(1.0, abs=1e-3)    # |a| matches |a_ref - g|
    # a stale reference (no update for > 0.5 s) is no longer used
    q_stale, _, _ = aided.run(np.zeros((10_000, 3)), np.tile(f_frd, (10_000, 1)), DT)
    assert np.degrees(tilt_error(q_stale[-1], q_true)) > 5
