"""The waypoint S-curve and the kinematic shaping respect their limits and end where told.

Sampled finely (1 ms) so a limit broken between outer-loop steps would show; jerk is the
finite difference of the sampled acceleration.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from silbridge.fc_sil.nav_kinematics import shape_vel_accel_xy, sqrt_controller
from silbridge.fc_sil.nav_scurve import SCurve
from silbridge.fc_sil.nav_wp import WaypointNav, WpSpeeds

DT = 0.001
ACCEL, JERK = 2.5, 1.0          # WPNAV_ACCEL / 100 and WPNAV_JERK defaults


def _sample(curve: SCurve) -> np.ndarray:
    t = np.arange(0.0, curve.duration_s + 1.0, DT)
    return np.array([curve.at(x) for x in t])


SNAP = 5.236    # AC_WPNav's snap at the defaults: 0.5 * pi * WPNAV_JERK / (2 * ATC_INPUT_TC)


@pytest.mark.parametrize("snap", [0.0, SNAP])
@pytest.mark.parametrize("length_m,speed_m_s,v0", [
    (30.0, 10.0, 0.0),        # the goto: too short to reach WPNAV_SPEED
    (200.0, 10.0, 0.0),       # cruises at WPNAV_SPEED
    (0.3, 10.0, 0.0),         # a tiny step
    (50.0, 5.0, 3.0),         # starts moving along the leg
])
def test_scurve_limits_and_exact_stop(length_m, speed_m_s, v0, snap):
    c = SCurve(length_m, speed_m_s, ACCEL, JERK, v0, snap)
    r = _sample(c)
    s, v, a = r[:, 0], r[:, 1], r[:, 2]
    jerk = np.diff(a) / DT
    assert v.max() <= speed_m_s + 1e-9
    assert np.abs(a).max() <= ACCEL + 1e-9
    assert np.abs(jerk).max() <= JERK * (1 + 1e-6)
    if snap:
        assert np.abs(np.diff(jerk)[1:] / DT).max() <= snap * 1.01
    assert v.min() >= -1e-9, "never backs up"
    assert np.all(np.diff(s) >= -1e-12) and s.max() <= length_m + 1e-9
    assert s[-1] == pytest.approx(length_m, abs=1e-9) and v[-1] == 0.0 and a[-1] == 0.0
    # continuity of the speed (no step at a segment boundary)
    assert np.abs(np.diff(v)).max() <= ACCEL * DT * 1.01


def test_scurve_is_fast_when_there_is_room():
    c = SCurve(200.0, 10.0, ACCEL, JERK)
    assert c.v_peak == pytest.approx(10.0)
    short = SCurve(30.0, 10.0, ACCEL, JERK)
    # the largest peak that still stops in 30 m: raising it by 1 % would need more room
    assert 5.0 < short.v_peak < 10.0
    assert short.duration_s < 11.0


def test_waypoint_nav_with_a_perfect_follower_stops_on_the_destination():
    wp = WaypointNav(WpSpeeds(speed_m_s=5.0, up_m_s=1.0, dn_m_s=1.0, accel_m_s2=2.5,
                              radius_m=2.0, jerk_m_s3=1.0, accel_z_m_s2=1.0))
    wp.set_destination((0.0, 0.0), 10.0, (30.0, 40.0), 20.0)
    pos, alt, vel = (0.0, 0.0), 10.0, (0.0, 0.0)
    acc_seen = []
    for _ in range(5000):
        tp, tv, ta, talt = wp.update(0.02, pos, alt, vel, 0.0)
        assert math.hypot(*tv) <= 5.0 + 1e-9
        acc_seen.append(math.hypot(*ta))
        pos, alt, vel = tp, talt, tv
    assert wp.reached(pos, alt)
    assert pos == pytest.approx((30.0, 40.0)) and alt == pytest.approx(20.0)
    assert max(acc_seen) <= 2.5 + 1e-9
    assert wp.bearing_rad == pytest.approx(math.atan2(40.0, 30.0))


def test_waypoint_clock_slows_while_the_vehicle_lags():
    wp = WaypointNav(WpSpeeds(jerk_m_s3=1.0))
    wp.set_destination((0.0, 0.0), 10.0, (100.0, 0.0), 10.0)
    for _ in range(400):                       # the vehicle never moves: 8 s
        wp.update(0.02, (0.0, 0.0), 10.0, (0.0, 0.0), 0.0)
    free = WaypointNav(WpSpeeds(jerk_m_s3=1.0))
    free.set_destination((0.0, 0.0), 10.0, (100.0, 0.0), 10.0)
    pos, vel = (0.0, 0.0), (0.0, 0.0)
    for _ in range(400):                       # a vehicle exactly on the target point
        pos, vel, _, _ = free.update(0.02, pos, 10.0, vel, 0.0)
    assert wp.s_m < 0.5 * free.s_m, (wp.s_m, free.s_m)
    assert wp.clock_rate < 0.2


def test_sqrt_controller_never_passes_zero_in_one_step():
    assert sqrt_controller(0.5, 1.0, 2.5) == pytest.approx(0.5)
    far = sqrt_controller(100.0, 1.0, 2.5)
    assert far == pytest.approx(math.sqrt(2 * 2.5 * (100.0 - 2.5 / 2)))
    assert sqrt_controller(-100.0, 1.0, 2.5) == pytest.approx(-far)
    assert sqrt_controller(0.001, 100.0, 0.0, 0.02) == pytest.approx(0.001 / 0.02)


def test_velocity_shaping_respects_accel_and_jerk_and_settles():
    vel, acc = (0.0, 0.0), (0.0, 0.0)
    accels, dt = [], 0.0025
    for _ in range(int(12.0 / dt)):
        acc = shape_vel_accel_xy((5.0, 0.0), (0.0, 0.0), vel, acc, ACCEL, 5.0, dt, False)
        vel = (vel[0] + acc[0] * dt, vel[1] + acc[1] * dt)
        accels.append(acc[0])
    a = np.array(accels)
    assert np.abs(a).max() <= ACCEL + 1e-9
    assert np.abs(np.diff(a)).max() <= 5.0 * dt + 1e-12
    assert vel[0] == pytest.approx(5.0, abs=0.01)
    assert a.min() > -0.05 * ACCEL, "no overshoot of the commanded speed worth a brake"


def test_a_climb_is_not_slowed_by_the_altitude_controller_lag():
    """The vertical target goes to the C core's altitude loop, which lags a climbing target
    (no climb-rate feed-forward): only horizontal lag may slow the clock."""
    wp = WaypointNav(WpSpeeds())
    wp.set_destination((0.3, -0.2), 6.0, (0.0, 0.0), 12.0)     # RTL's climb: nearly vertical
    for _ in range(200):
        wp.update(0.02, (0.0, 0.0), 6.0, (0.0, 0.0), 0.0)     # the vehicle has not climbed yet
    assert wp.clock_rate == pytest.approx(1.0)
