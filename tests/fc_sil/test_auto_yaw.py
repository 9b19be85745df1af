"""AutoYaw and HeadingControl (fc_sil/auto_yaw.py): ArduCopter's yaw modes and the heading loop
the navigation modes need while the core's ATC_ANG_YAW_P is 0."""

from __future__ import annotations

import math

from silbridge.fc_sil.auto_yaw import AutoYaw, HeadingControl, YawConfig, YawMode

DT = 0.02
SLEW = math.radians(60.0)


def _walk(a: AutoYaw, seconds: float, shaped: float = 0.0):
    out = []
    for _ in range(int(seconds / DT)):
        out.append(a.target(DT, shaped, (0.0, 0.0), 10.0, (0.0, 0.0))[0])
    return out


def test_condition_yaw_absolute_takes_the_short_way_at_the_slew_rate():
    a = AutoYaw(math.radians(350.0) - 2 * math.pi)
    a.set_fixed(math.radians(20.0), 0.0, 0, False, SLEW, a.yaw_rad)
    path = _walk(a, 1.0)
    steps = [abs(math.remainder(b - c, 2 * math.pi)) for b, c in zip(path[1:], path)]
    assert max(steps) <= SLEW * DT + 1e-9
    assert math.isclose(math.degrees(path[-1]) % 360.0, 20.0, abs_tol=1e-6)   # 30 deg, 0.5 s
    assert a.reached_fixed(path[-1])


def test_condition_yaw_direction_forces_the_long_way_and_rate_slows_it():
    a = AutoYaw(0.0)
    a.set_fixed(math.radians(90.0), math.radians(30.0), -1, False, SLEW, 0.0)
    assert math.isclose(a.fixed_offset_rad, math.radians(-270.0))
    path = _walk(a, 1.0)
    assert math.isclose(math.degrees(path[-1]), -30.0, abs_tol=1e-6)


def test_relative_yaw_counts_from_the_present_heading_when_holding():
    a = AutoYaw(0.0)
    a.set_fixed(math.radians(-45.0), 0.0, 0, True, SLEW, math.radians(100.0))
    path = _walk(a, 2.0)
    assert math.isclose(math.degrees(path[-1]), 55.0, abs_tol=1e-6)


def test_look_at_next_wp_faces_the_desired_velocity_above_five_percent():
    a = AutoYaw(0.0)
    a.set_default(2, 0.0)
    assert a.mode == YawMode.LOOK_AT_NEXT_WP
    yaw, _, angle = a.target(DT, 0.3, (0.0, 2.0), 10.0, (0.0, 0.0))
    assert angle and math.isclose(yaw, math.pi / 2)
    yaw, _, _ = a.target(DT, 0.3, (0.0, 0.4), 10.0, (0.0, 0.0))      # under 0.5 m/s: hold
    assert yaw == 0.3
    a.set_default(0, 0.0)
    assert a.mode == YawMode.HOLD


def test_heading_control_gives_a_rate_only_when_the_core_holds_no_heading():
    cfg = YawConfig(slew_max_rad_s=SLEW, core_ang_p=0.0)
    h = HeadingControl(0.0)
    rates = [h.update(DT, cfg, 0.0, math.pi / 2, 0.0, True)[1] for _ in range(100)]
    assert all(r is not None for r in rates)
    assert abs(h.rate_rad_s) <= SLEW + 1e-9
    assert rates[-1] > 0.0                 # the vehicle has not turned: the loop pushes on
    held = HeadingControl(0.0)
    out = [held.update(DT, YawConfig(slew_max_rad_s=SLEW, core_ang_p=4.5), 0.0, math.pi / 2,
                       0.0, True) for _ in range(150)]
    assert all(r is None for _, r in out)
    assert math.isclose(out[-1][0], math.pi / 2, abs_tol=math.radians(0.5))
