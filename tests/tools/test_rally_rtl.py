"""RTL goes to the nearest rally point (RALLY_INCL_HOME: unless home is closer), on silbridge
and (SILBRIDGE_ARDUCOPTER set) the real ArduCopter 4.6; and on silbridge the fence and rally
lists persist beside the mission file (`--mission FILE` -> FILE.fence, FILE.rally).

Flight: rally point 45 m north at 12 m, take off to 8 m, fly 70 m north, RTL: the rally point
is 25 m away and home 70 m, so the vehicle lands at the rally point.
"""

from __future__ import annotations

import math
import os
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, Silbridge, start  # noqa: E402
from gcs_session import Gcs, offset_e7  # noqa: E402

RALLY = mav.MAV_MISSION_TYPE_RALLY


def _north_m(lat_e7: int, home_lat_e7: int) -> float:
    return (lat_e7 - home_lat_e7) * 1e-7 * 111319.5


@pytest.mark.parametrize("kind", KINDS)
def test_rtl_lands_at_the_nearest_rally_point(kind, tmp_path):
    ap = start(kind, tmp_path, arducopter_params={"AVOID_ENABLE": 0})
    g = None
    try:
        g = Gcs(ap.pymavlink_url)
        g.streams(10)
        home = g.wait("GLOBAL_POSITION_INT", lambda p: p.lat != 0, 60.0)
        assert home is not None
        rlat, rlon = offset_e7(home.lat / 1e7, home.lon / 1e7, 45.0, 0.0)
        ack = g.upload(RALLY, [dict(frame=mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                                    command=mav.MAV_CMD_NAV_RALLY_POINT, x=rlat, y=rlon,
                                    z=12.0)])
        assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED, ack
        g.arm_and_takeoff(8.0)
        assert g.wait_alt(6.5, 60.0)
        home = g.last.get("HOME_POSITION") or home
        home_lat = home.latitude if hasattr(home, "latitude") else home.lat
        g.fly_velocity(5.0, 0.0, 40.0, stop=lambda: g.last["GLOBAL_POSITION_INT"].lat
                       and _north_m(g.last["GLOBAL_POSITION_INT"].lat, home_lat) > 70.0)
        p = g.rtl_until_landed(90.0)
        n = _north_m(p.lat, home_lat)
        e = (p.lon - home.lon if hasattr(home, "lon") else p.lon - home.longitude) * 1e-7 \
            * 111319.5 * math.cos(math.radians(p.lat * 1e-7))
        assert abs(n - 45.0) < 6.0 and abs(e) < 6.0, f"landed at {n:.1f} m N, {e:.1f} m E"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if g is not None:
            g.close()
        ap.stop()


def test_fence_and_rally_persist_beside_the_mission_file(tmp_path):
    mission = tmp_path / "plan.txt"
    lat, lon = 473977420, 85455940
    fence = [dict(frame=mav.MAV_FRAME_GLOBAL_INT, command=mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
                  p1=80.0, x=lat, y=lon)]
    rally = [dict(frame=mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                  command=mav.MAV_CMD_NAV_RALLY_POINT, x=lat + 3000, y=lon, z=15.0)]
    for round_ in range(2):
        ap = Silbridge(extra=("--mission", str(mission)), cwd=str(tmp_path))
        g = None
        try:
            g = Gcs(ap.pymavlink_url)
            if round_ == 0:
                for mtype, items in ((mav.MAV_MISSION_TYPE_FENCE, fence), (RALLY, rally)):
                    ack = g.upload(mtype, items)
                    assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED
                g.pump(0.5)
            else:
                got = g.download(mav.MAV_MISSION_TYPE_FENCE)
                assert [(i.command, i.param1, i.x, i.y) for i in got] == \
                    [(mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, 80.0, lat, lon)]
                got = g.download(RALLY)
                assert [(i.x, i.y, i.z) for i in got] == [(lat + 3000, lon, 15.0)]
                assert g.get_param("RALLY_TOTAL") == 1
        finally:
            if g is not None:
                g.close()
            err = ap.stop()
        assert "Traceback" not in err, err[-2000:]
    assert (tmp_path / "plan.txt.fence").exists() and (tmp_path / "plan.txt.rally").exists()
