"""Spline legs (nav_spline.py) and circles (nav_circle.py): geometry and the limits on the
target point, driven step by step as the vehicle drives them (50 Hz)."""

from __future__ import annotations

import math

import pytest

from silbridge.fc_sil.nav_circle import CircleNav
from silbridge.fc_sil.nav_spline import SplineLeg, SplineLimits, SplineNav, kinematic_limit

DT = 0.02
LIM = SplineLimits()          # ArduCopter's defaults: 10 m/s, 2.5 up, 1.5 down, 2.5 m/s^2


def _unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def _close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def test_kinematic_limit_keeps_each_axis_within_its_limit():
    assert kinematic_limit((1, 0, 0), 10, 2.5, 1.5) == pytest.approx(10.0)
    assert kinematic_limit((0, 0, 1), 10, 2.5, 1.5) == pytest.approx(2.5)
    assert kinematic_limit((0, 0, -1), 10, 2.5, 1.5) == pytest.approx(1.5)
    # 45 deg climb: the vertical limit binds (2.5 / sin 45)
    assert kinematic_limit((1, 0, 1), 10, 2.5, 1.5) == pytest.approx(2.5 * math.sqrt(2))
    assert kinematic_limit((0, 0, 0), 10, 2.5, 1.5) == 0.0


def test_leg_passes_through_its_ends_with_the_given_tangents():
    leg = SplineLeg((0, 0, 10), (20, 20, 12), (30, 0, 0), (0, 40, 0), LIM)
    p0, v0, _, _ = leg.eval(0.0)
    p1, v1, _, _ = leg.eval(1.0)
    assert _close(p0, (0, 0, 10)) and _close(p1, (20, 20, 12))
    assert _close(_unit(v0), (1, 0, 0)) and _close(_unit(v1), (0, 1, 0))


def test_consecutive_legs_join_with_one_tangent():
    # as the mission builds them: leg 2 leaves along the vector leg 1 arrived with
    a, b, c, d = (0, 0, 10), (20, 20, 12), (0, 40, 10), (-20, 40, 10)
    v_b = tuple(y - x for x, y in zip(a, c))          # next is a spline: origin -> next dest
    v_c = tuple(y - x for x, y in zip(c, d))          # next is straight: along it
    leg1 = SplineLeg(a, b, (0, 0, 0), v_b, LIM)
    leg2 = SplineLeg(b, c, v_b, v_c, LIM)
    assert _close(leg1.eval(1.0)[0], leg2.eval(0.0)[0])
    assert _close(_unit(leg1.eval(1.0)[1]), _unit(leg2.eval(0.0)[1]))


def test_long_end_vectors_are_scaled_so_a_short_leg_does_not_loop():
    leg = SplineLeg((0, 0, 0), (2, 0, 0), (0, 100, 0), (0, -100, 0), LIM)
    v0 = math.sqrt(sum(x * x for x in leg.eval(0.0)[1]))
    v1 = math.sqrt(sum(x * x for x in leg.eval(1.0)[1]))
    assert v0 + v1 == pytest.approx(4.0 * 2.0)       # four chords at most
    far = max(abs(leg.eval(t / 100)[0][1]) for t in range(101))
    assert far < 2.0


def _fly(nav, seconds, follow=True):
    """Drive the target with a vehicle that sits on it; returns the samples."""
    out = []
    pos, alt = nav.leg.origin[:2], nav.leg.origin[2]
    for _ in range(int(seconds / DT)):
        tp, tv, talt = nav.update(DT, pos, alt, (*tv_prev(out), 0.0))
        out.append((tp, tv, talt, nav.speed_m_s))
        if follow:
            pos, alt = tp, talt
        if nav.reached(pos, alt):
            break
    return out


def tv_prev(out):
    return out[-1][1] if out else (0.0, 0.0)


def test_target_keeps_speed_cornering_and_braking_limits_and_stops_at_the_end():
    nav = SplineNav(LIM)
    nav.set_leg((30, 0, 10), (50, 20, 10), (30, 0, 0), (0, 0, 0))
    out = _fly(nav, 60.0)
    assert nav.reached(out[-1][0], out[-1][2]), "never got there"
    speeds = [s for *_, s in out]
    assert max(speeds) <= LIM.speed_xy_m_s + 1e-6
    # speed changes at most half WPNAV_ACCEL per second
    dv = max(abs(b - a) for a, b in zip(speeds, speeds[1:])) / DT
    assert dv <= 0.5 * LIM.accel_xy_m_s2 + 1e-6
    # the path's cornering acceleration v^2 * curvature stays within half WPNAV_ACCEL
    for t in [i / 50 for i in range(1, 50)]:
        _, v, a, _ = nav.leg.eval(t)
        vl = math.sqrt(sum(x * x for x in v))
        a_along = sum(x * y for x, y in zip(a, v)) / vl
        an = math.sqrt(max(0.0, sum(x * x for x in a) - a_along ** 2))
        v_allowed = nav.leg.limits_at(t, 0.0)[2]
        assert v_allowed ** 2 * an / vl ** 2 <= 0.5 * LIM.accel_xy_m_s2 + 1e-6
    # ends braking to rest (the mission stops here): the last step leaves at most the speed of
    # the braking curve 10 cm out, sqrt(2 * 0.5 a * 0.1)
    assert speeds[-1] <= math.sqrt(2 * 0.5 * LIM.accel_xy_m_s2 * 0.1), speeds[-1]
    assert math.dist(out[-1][0], (50, 20)) < 0.05 and abs(out[-1][2] - 10) < 0.05


def test_a_leg_that_flies_on_arrives_moving_and_counts_as_reached_at_once():
    nav = SplineNav(LIM)
    nav.set_leg((0, 0, 10), (20, 20, 10), (0, 0, 0), (0, 40, 0))
    assert nav.ends_moving
    out = _fly(nav, 60.0)
    assert nav.target_done() and nav.reached(out[-1][0], out[-1][2])
    assert out[-1][3] > 2.0, "a fast waypoint does not stop"
    assert out[-1][3] <= nav.leg.dest_speed_max + 1e-6


def test_climbing_leg_keeps_the_climb_rate_limit():
    nav = SplineNav(LIM)
    nav.set_leg((0, 0, 10), (10, 0, 30), (0, 0, 0), (0, 0, 0))
    out = _fly(nav, 60.0)
    climbs = [(b[2] - a[2]) / DT for a, b in zip(out, out[1:])]
    assert max(climbs) <= LIM.speed_up_m_s * 1.01
    assert nav.reached(out[-1][0], out[-1][2])


def test_target_waits_for_a_vehicle_that_does_not_follow():
    nav = SplineNav(LIM)
    nav.set_leg((0, 0, 10), (100, 0, 10), (0, 0, 0), (0, 0, 0))
    out = _fly(nav, 20.0, follow=False)
    lead = math.dist(out[-1][0], (0, 0))
    assert lead < 15.0, f"the target ran {lead:.1f} m ahead of a vehicle that stayed put"
    assert nav.time_scale < 0.2


def test_circle_rate_is_limited_by_speed_and_half_the_acceleration():
    c = CircleNav((0, 40), 10.0, math.radians(20.0), 10.0, 2.5)
    # sqrt(0.5 * 2.5 * 10) = 3.54 m/s -> 0.354 rad/s: CIRCLE_RATE 20 deg/s (0.349) binds
    assert c.angular_vel_max == pytest.approx(math.radians(20.0))
    c = CircleNav((0, 40), 10.0, math.radians(90.0), 10.0, 2.5)
    assert c.angular_vel_max * 10.0 == pytest.approx(math.sqrt(0.5 * 2.5 * 10.0))


def test_circle_starts_at_the_vehicle_turns_clockwise_and_counts_turns():
    c = CircleNav((0, 40), 10.0, math.radians(20.0), 10.0, 2.5)
    c.start((10, 40), 0.0)                # north of the centre
    p, v, a = c.update(DT)
    assert math.dist(p, (10, 40)) < 0.01
    for _ in range(int(5.0 / DT)):
        p, v, a = c.update(DT)
    assert p[1] > 40.0, "clockwise from north goes east"
    assert math.dist(p, (0, 40)) == pytest.approx(10.0)
    speed = math.hypot(*v)
    assert speed == pytest.approx(10.0 * math.radians(20.0), rel=1e-6)
    assert math.hypot(*a) == pytest.approx(speed ** 2 / 10.0, rel=1e-6)   # centripetal
    n = 0
    while c.turns_done < 1.0 and n < 100_000:
        c.update(DT)
        n += 1
    assert math.dist(c.target(), (10, 40)) < 0.2, "one turn ends where it began"
    ccw = CircleNav((0, 40), 10.0, -math.radians(20.0), 10.0, 2.5)
    ccw.start((10, 40), 0.0)
    for _ in range(int(5.0 / DT)):
        p, _, _ = ccw.update(DT)
    assert p[1] < 40.0


def test_circle_edge_is_the_nearest_point_of_the_circle():
    c = CircleNav((0, 40), 10.0, 0.3, 10.0, 2.5)
    assert _close(c.closest_edge((30, 40), 0.0), (10, 40))
    assert _close(c.closest_edge((0, 40), 0.0), (-10, 40))   # at the centre: behind the nose
