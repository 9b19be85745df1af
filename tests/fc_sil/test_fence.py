"""Geofence and rally logic (fc_sil/fence.py, fc_sil/rally.py) step by step, on the vehicle
state they read: what breaches, which action, the backup fence, manual recovery, the pre-arm
wording, union vs intersection of inclusion areas, and which rally point RTL picks.
The flights into each fence type on the whole vehicle are tests/tools/test_geofence_flight.py.
"""

from __future__ import annotations

from types import SimpleNamespace

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.fence import Geofence
from silbridge.fc_sil.pos_est import GeoOrigin
from silbridge.fc_sil.rally import RallyPoints
from silbridge.mavlink.gcs.vehicle_api import CopterMode, MissionItem

ORIGIN = GeoOrigin(-353632621, 1491652374, 584.0)
PARAMS = {"FENCE_ENABLE": 1, "FENCE_TYPE": 7, "FENCE_ACTION": 1, "FENCE_ALT_MAX": 100.0,
          "FENCE_ALT_MIN": -10.0, "FENCE_RADIUS": 300.0, "FENCE_MARGIN": 2.0,
          "FENCE_AUTOENABLE": 0, "FENCE_OPTIONS": 0, "RALLY_LIMIT_KM": 0.3,
          "RALLY_INCL_HOME": 1}


class Vehicle(SimpleNamespace):
    """The vehicle state the fence reads, and the three requests it makes."""

    def __init__(self, **kw):
        state = dict(armed=True, airborne=True, takeoff_in_progress=False, landing=False,
                     alt_m=10.0, home_set=True, home_ne=(0.0, 0.0), home_alt_msl_m=584.0,
                     sim_ns=10**9, mode=SimpleNamespace(number=CopterMode.GUIDED),
                     est=SimpleNamespace(origin=ORIGIN, pos_ne_m=[0.0, 0.0]),
                     texts=[], modes=[], disarmed=False, home_up_m=0.0)
        super().__init__(**{**state, **kw})

    def alt_from_home(self, alt_rel_m):
        return alt_rel_m + self.home_up_m

    def alt_from_msl(self, alt_msl_m):
        return alt_msl_m - (self.home_alt_msl_m - self.home_up_m)

    def position_ok(self):
        return True

    def statustext(self, sev, text):
        self.texts.append(text)

    def fence_disarm(self):
        self.disarmed = True

    def fence_set_mode(self, number):
        self.modes.append(number)
        self.mode = SimpleNamespace(number=number)
        return True


def fence(**params):
    f = Geofence()
    f.configure(lambda n: {**PARAMS, **params}[n])
    return f


def at(n, e):
    return ORIGIN.to_latlon_e7(n, e)


def poly(cmd, pts, first=0):
    return [MissionItem(first + i, mav.MAV_FRAME_GLOBAL_INT, cmd, param1=len(pts), x=at(*p)[0],
                        y=at(*p)[1], mission_type=1) for i, p in enumerate(pts)]


def test_alt_max_breach_rtl_backup_fence_and_recovery():
    f, v = fence(FENCE_TYPE=1, FENCE_ALT_MAX=30.0), Vehicle()
    f.check(v)
    assert f.breaches == 0 and f.sys_status(v) == (True, True, True)
    v.alt_m = 31.0
    f.check(v)
    assert v.texts == ["Max Alt fence breached"] and v.modes == [CopterMode.RTL]
    assert f.breach_type == mav.FENCE_BREACH_MAXALT and f.sys_status(v) == (True, True, False)
    f.manual_recovery_start(v)                  # the vehicle's mode change does this
    v.alt_m = 45.0                              # still breached, below the +20 m backup
    f.check(v)
    assert f.breach_count == 1
    v.alt_m = 52.0                              # through the backup fence: a new breach,
    f.check(v)                                  # recorded but no action while recovering
    assert f.breach_count == 2 and v.modes == [CopterMode.RTL]
    v.alt_m = 29.5                              # inside, but within 1 m of the line
    f.check(v)
    assert f.breaches
    v.alt_m = 28.0
    f.check(v)
    assert f.breaches == 0 and v.texts[-1] == "Fence breach cleared"
    assert f.breach_type == mav.FENCE_BREACH_NONE


def test_altitude_fences_are_above_a_home_a_gcs_moved():
    """DO_SET_HOME 12 m above the take-off point: FENCE_ALT_MAX and the destinations GUIDED
    accepts count from the new home, not from where the vehicle armed."""
    f, v = fence(FENCE_TYPE=1, FENCE_ALT_MAX=30.0), Vehicle(home_up_m=12.0)
    v.alt_m = 40.0                               # 28 m above home
    f.check(v)
    assert f.breaches == 0 and f.destination_ok(v, (0.0, 0.0), 41.0)
    assert not f.destination_ok(v, (0.0, 0.0), 43.0)
    v.alt_m = 42.5
    f.check(v)
    assert v.texts == ["Max Alt fence breached"]


def test_actions_landed_disarm_give_up_and_report_only():
    f, v = fence(FENCE_TYPE=2, FENCE_RADIUS=50.0, FENCE_ACTION=4), Vehicle()
    v.est.pos_ne_m = [60.0, 0.0]
    f.check(v)
    assert v.modes == [CopterMode.BRAKE]
    f, v = fence(FENCE_TYPE=2, FENCE_RADIUS=50.0, FENCE_ACTION=1), Vehicle()
    v.est.pos_ne_m = [200.0, 0.0]               # > 100 m outside: ArduCopter just lands
    f.check(v)
    assert v.modes == [CopterMode.LAND]
    f, v = fence(FENCE_TYPE=2, FENCE_RADIUS=50.0), Vehicle(airborne=False)
    v.est.pos_ne_m = [60.0, 0.0]
    f.check(v)
    assert v.disarmed and v.modes == []
    f, v = fence(FENCE_TYPE=2, FENCE_RADIUS=50.0, FENCE_ACTION=0), Vehicle()
    v.est.pos_ne_m = [60.0, 0.0]
    f.check(v)
    assert v.texts == ["Circle fence breached"] and v.modes == []
    assert f.sys_status(v) == (True, False, False)   # report only: present, not "enabled"


def test_polygons_intersection_union_and_exclusion():
    incl_a = poly(mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                  [(-50, -50), (50, -50), (50, 50), (-50, 50)])
    incl_b = poly(mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                  [(30, -20), (120, -20), (120, 20), (30, 20)], first=4)
    excl = [MissionItem(8, mav.MAV_FRAME_GLOBAL_INT, mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
                        param1=10.0, x=at(-30, -30)[0], y=at(-30, -30)[1], mission_type=1)]
    for options, expect_at_80 in ((0, True), (2, False)):
        f, v = fence(FENCE_TYPE=4, FENCE_OPTIONS=options), Vehicle()
        f.set_items(incl_a + incl_b + excl)
        v.est.pos_ne_m = [40.0, 0.0]                # inside both
        assert not f._polygon_breached(v, v.est.pos_ne_m)
        assert f._polygon_breached(v, [80.0, 0.0]) is expect_at_80   # only inside b
        assert f._polygon_breached(v, [-30.0, -25.0])                 # in the exclusion
    f, v = fence(FENCE_TYPE=4), Vehicle()
    f.set_items(excl)
    v.est.pos_ne_m = [-30.0, -30.0]
    f.check(v)
    assert v.texts == ["Polygon fence breached"] and f.breach_type == mav.FENCE_BREACH_BOUNDARY
    assert not f.destination_ok(v, (-32.0, -30.0), 10.0)
    assert f.destination_ok(v, (20.0, 20.0), 10.0)


def test_prearm_wording_and_presence():
    v = Vehicle(armed=False, airborne=False)
    assert fence(FENCE_TYPE=4).prearm_failure(v) == "PreArm: Fences enabled, but none selected"
    assert not fence(FENCE_TYPE=4).present()
    assert fence(FENCE_TYPE=2, FENCE_RADIUS=1.0).prearm_failure(v) == \
        "PreArm: Circle FENCE_MARGIN is less than FENCE_RADIUS"
    assert fence(FENCE_TYPE=1, FENCE_ALT_MAX=3.0, FENCE_ALT_MIN=0.0).prearm_failure(v) \
        == "PreArm: FENCE_MARGIN too big"
    f = fence(FENCE_TYPE=2, FENCE_RADIUS=30.0)
    v.est.pos_ne_m = [40.0, 0.0]
    f.check(v)                                  # breached while disarmed: not announced
    assert v.texts == [] and f.prearm_failure(v) == "PreArm: Vehicle breaching Circle fence"
    assert fence(FENCE_ENABLE=0).prearm_failure(v) is None


def test_rally_point_choice():
    r = RallyPoints()
    r.configure(lambda n: PARAMS[n])
    rel = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    near, far = at(100, 0), at(0, 400)          # the second beyond RALLY_LIMIT_KM from home
    r.set_items([MissionItem(0, rel, 5100, x=near[0], y=near[1], z=25.0),
                 MissionItem(1, rel, 5100, x=far[0], y=far[1], z=25.0)])
    v = Vehicle()
    v.est.pos_ne_m = [150.0, 0.0]
    t = r.rtl_destination(v)
    assert t.rally_index == 0 and abs(t.ne[0] - 100.0) < 0.5 and t.alt_m == 25.0
    v.est.pos_ne_m = [0.0, 390.0]               # near the far point, but it is out of range
    assert r.rtl_destination(v).rally_index is None
    v.est.pos_ne_m = [30.0, 0.0]                # home is closer than the rally point
    assert r.rtl_destination(v).rally_index is None
    r.incl_home = 0
    assert r.rtl_destination(v).rally_index == 0
