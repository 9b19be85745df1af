"""A guided goto stops at the point: the same MAVSDK script against silbridge and ArduCopter 4.6.

The script a new user writes: take off to 10 m, `Action.goto_location` to a point 30 m north,
watch the position stream. At default WPNAV_* both autopilots must arrive (within
WPNAV_RADIUS, 2 m) and, until they first stop there, pass the point by less than 0.5 m
(issue 23; before the S-curve legs silbridge passed it by 5.7 m at 9.3 m/s). The later
wander while holding (GNSS noise through the estimate) is printed, not asserted. The real
ArduCopter runs when SILBRIDGE_ARDUCOPTER names its SITL binary, else its case is skipped.

Positions are the autopilot's own estimate (GLOBAL_POSITION_INT through MAVSDK), as the
user sees them; the figures are printed for the docs (pytest -s).
"""

from __future__ import annotations

import math
import os
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

import waits  # noqa: E402
from waits import accepted  # noqa: E402


def until(pred, timeout_s, step_s=0.1):      # this file polls faster than waits.until's default
    return waits.until(pred, timeout_s, step_s)


import autopilots  # noqa: E402

from silbridge.tools.benchmark.nav.plans import PHYSICS_DIR  # noqa: E402

mavsdk = pytest.importorskip("mavsdk")
if not hasattr(mavsdk, "Mavsdk"):
    pytest.skip("these tests use the MAVSDK 4.x Python binding (pip install 'mavsdk>=4')",
                allow_module_level=True)

from mavsdk import ComponentType, Configuration, Mavsdk  # noqa: E402
from mavsdk.plugins.action import Action  # noqa: E402
from mavsdk.plugins.telemetry import Telemetry  # noqa: E402

mavsdk.log_subscribe(lambda level, msg, file, line: True)

GOTO_NORTH_M = 30.0
TAKEOFF_M = 10.0
M_PER_DEG_LAT = 111_320.0


def _north_east(p, lat0, lon0):
    return ((p.latitude_deg - lat0) * M_PER_DEG_LAT,
            (p.longitude_deg - lon0) * M_PER_DEG_LAT * math.cos(math.radians(lat0)))


def _fly_goto(url: str) -> dict:
    m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        m.add_any_connection(url)
        system = m.first_autopilot(60.0)
        assert system is not None, "MAVSDK found no autopilot"
        tel, action = Telemetry(system), Action(system)
        tel.set_rate_position(20.0)
        tel.set_rate_velocity_ned(20.0)
        # ArduCopter's SYS_STATUS health bits never satisfy MAVSDK's health_all_ok: wait for
        # a home position, then arm and take off as soon as the autopilot accepts both
        assert until(lambda: tel.health().is_home_position_ok, 120.0, 0.5), tel.health()
        action.set_takeoff_altitude(TAKEOFF_M)
        assert until(lambda: accepted(action.arm) and accepted(action.takeoff), 120.0, 1.0), \
            "did not arm and take off"
        assert until(lambda: tel.position().relative_altitude_m > TAKEOFF_M - 0.5, 90.0)
        assert until(lambda: math.hypot(tel.velocity_ned().north_m_s,
                                         tel.velocity_ned().east_m_s) < 0.2
                      and abs(tel.velocity_ned().down_m_s) < 0.2, 60.0)
        time.sleep(2.0)       # let the take-off's transient settle (6-10 s of sim time)
        start = tel.position()
        lat0, lon0 = start.latitude_deg, start.longitude_deg
        target_lat = lat0 + GOTO_NORTH_M / M_PER_DEG_LAT
        action.goto_location(target_lat, lon0, start.absolute_altitude_m, float("nan"))
        north, speed, arrived, stopped = [], [], None, None
        end = time.monotonic() + 120.0
        while time.monotonic() < end:
            n, e = _north_east(tel.position(), lat0, lon0)
            v = tel.velocity_ned()
            north.append(n)
            speed.append(math.hypot(v.north_m_s, v.east_m_s))
            if arrived is None and math.hypot(n - GOTO_NORTH_M, e) <= 2.0:
                arrived = len(north)
            if arrived is not None and stopped is None and speed[-1] < 0.2:
                stopped = len(north)          # the first stop at the point
            if stopped is not None and len(north) - stopped > 100:
                break                         # and a while holding there
            time.sleep(0.02)
        assert stopped is not None, "never stopped at the point"
        return dict(overshoot_m=max(north[:stopped]) - GOTO_NORTH_M,
                    hold_max_m=max(north[stopped:]) - GOTO_NORTH_M,
                    peak_speed_m_s=max(speed), final_error_m=abs(north[-1] - GOTO_NORTH_M),
                    arrived=arrived is not None)
    finally:
        m.destroy()


# GUID_OPTIONS 0 (default): ArduCopter flies a position target with its position controller's
# input shaping (PSC_JERK_XY); 64: with the waypoint navigator's S-curve (WPNAV_JERK).
PATHS = {"shaped": 0, "scurve": 64}
# ArduCopter 4.6.0 itself passes the point by 0.64-0.65 m on its default path (its shaped
# path alone overshoots 0.19 m with a perfect follower; docs/explanation/nav-control.md)
_AC_SHAPED = pytest.mark.xfail(reason="ArduCopter 4.6.0 overshoots 0.64 m on its default "
                               "(shaped) goto path", strict=False)
CASES = [pytest.param(kind, path, marks=_AC_SHAPED if (kind, path) == ("arducopter", "shaped")
                      else ()) for kind in autopilots.KINDS for path in PATHS]


@pytest.mark.parametrize("kind,path", CASES)
def test_guided_goto_stops_at_the_point(kind, path, tmp_path):
    opt = PATHS[path]
    # Our quad on the navigation benchmark's calm physics: GNSS without the slow position
    # walk, as ArduCopter's SITL GPS (built from its true position) has none; with the walk
    # our estimate wanders up to 0.7 m while holding, and that noise would be scored here as
    # overshoot.
    calm = str(PHYSICS_DIR / "nav_calm.toml")
    ap = autopilots.start(kind, tmp_path,
                          silbridge_extra=("--scenario", calm, "--param", f"GUID_OPTIONS={opt}"),
                          arducopter_params={"GUID_OPTIONS": opt})
    try:
        r = _fly_goto(ap.mavsdk_url)
    finally:
        tail = ap.stop()
    print(f"\n{kind} {path}: goto {GOTO_NORTH_M:g} m: overshoot {r['overshoot_m']:.2f} m, "
          f"peak speed {r['peak_speed_m_s']:.2f} m/s, final error {r['final_error_m']:.2f} m, "
          f"largest excursion while holding {r['hold_max_m']:.2f} m")
    assert r["arrived"], (r, tail[-1500:])
    assert r["overshoot_m"] < 0.5, r
    assert r["final_error_m"] < 2.0, r
