"""fc_attitude.c: small-angle errors and attitude-P rate targets."""

import numpy as np
import pytest

import fc_blocks as B


def q_euler(r, p, y):
    cr, sr, cp, sp, cy, sy = (np.cos(r / 2), np.sin(r / 2), np.cos(p / 2), np.sin(p / 2),
                              np.cos(y / 2), np.sin(y / 2))
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


def test_small_angle_errors_have_the_sign_of_target_minus_estimate():
    ex, ey, ez = B.attitude_error(q_euler(0.0, 0.0, 0.3), 0.05, -0.02)
    assert ex == pytest.approx(0.05, abs=1e-3)
    assert ey == pytest.approx(-0.02, abs=1e-3)
    assert ez == pytest.approx(0.0, abs=1e-3)   # yaw not held: second order only


def test_yaw_error_only_when_held():
    q = q_euler(0.0, 0.0, 0.1)
    assert B.attitude_error(q, 0, 0, 0.3, hold_yaw=True)[2] == pytest.approx(0.2, abs=1e-4)
    assert B.attitude_error(q, 0, 0, 0.3, hold_yaw=False)[2] == pytest.approx(0.0, abs=1e-6)
    # the short way round across +-pi
    e = B.attitude_error(q_euler(0, 0, 3.1), 0, 0, -3.1, hold_yaw=True)[2]
    assert e == pytest.approx(2 * np.pi - 6.2, abs=1e-3)


def test_rate_targets_are_p_times_error_limited_with_yaw_rate_feed_forward():
    r = B.rate_targets((0.1, -0.2, 0.05), ang_p=(4.5, 4.5, 0.0), yaw_rate_ff_rad_s=0.3)
    assert r == pytest.approx((0.45, -0.9, 0.3), abs=1e-6)
    r = B.rate_targets((1.0, -1.0, 0.0), ang_p=(4.5, 4.5, 0.0), rate_max_rad_s=(2.0, 3.0, 0.0))
    assert r == pytest.approx((2.0, -3.0, 0.0), abs=1e-6)
