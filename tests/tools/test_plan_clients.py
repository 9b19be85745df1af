"""A QGroundControl plan (mission + fence + rally) through pymavlink, home announcements, and the
fence pre-arm check, on silbridge and (SILBRIDGE_ARDUCOPTER set) the real ArduCopter 4.6.

* the plan: uploaded as QGC does (MISSION_COUNT per mission_type, items on request), read back
  item for item, RALLY_TOTAL = the rally count; a bad fence upload (a polygon whose vertex
  count changes mid-polygon) is refused and the previous fence downloads unchanged; clearing a
  fence leaves the rally points;
* HOME_POSITION: not streamed unasked (ArduCopter sends it when home is set and at arming, and
  on request), once on GET_HOME_POSITION, once more when arming fixes home;
* pre-arm: FENCE_ENABLE 1 with only the polygon type and no fence uploaded refuses to arm, and
  so does a vehicle inside an exclusion circle ("Vehicle breaching Polygon fence"; a breach
  while disarmed is not announced).
"""

from __future__ import annotations

import os
import sys
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, start  # noqa: E402
from gcs_session import Gcs, offset_e7  # noqa: E402

FENCE, RALLY, MISSION = (mav.MAV_MISSION_TYPE_FENCE, mav.MAV_MISSION_TYPE_RALLY,
                         mav.MAV_MISSION_TYPE_MISSION)
G_INT, REL_INT = mav.MAV_FRAME_GLOBAL_INT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def _plan(lat: float, lon: float):
    def at(n, e):
        return offset_e7(lat, lon, n, e)
    mission = [dict(frame=G_INT, command=mav.MAV_CMD_NAV_WAYPOINT, x=at(0, 0)[0], y=at(0, 0)[1]),
               dict(frame=REL_INT, command=mav.MAV_CMD_NAV_TAKEOFF, z=10.0),
               dict(frame=REL_INT, command=mav.MAV_CMD_NAV_WAYPOINT, x=at(30, 0)[0],
                    y=at(30, 0)[1], z=10.0),
               dict(frame=REL_INT, command=mav.MAV_CMD_NAV_RETURN_TO_LAUNCH)]
    square = [(-50, -50), (50, -50), (50, 50), (-50, 50)]
    fence = [dict(frame=G_INT, command=mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, p1=4,
                  x=at(n, e)[0], y=at(n, e)[1]) for n, e in square]
    fence.append(dict(frame=G_INT, command=mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, p1=8.0,
                      x=at(30, 30)[0], y=at(30, 30)[1]))
    rally = [dict(frame=REL_INT, command=mav.MAV_CMD_NAV_RALLY_POINT, x=at(n, e)[0],
                  y=at(n, e)[1], z=z) for n, e, z in ((40, 0, 15.0), (0, -40, 20.0))]
    return mission, fence, rally


def _same(sent: list, got: list, what: str) -> None:
    assert len(got) == len(sent), f"{what}: {len(got)} items back, {len(sent)} sent"
    for s, g in zip(sent, got):
        assert g.command == s["command"], (what, g)
        assert abs(g.x - s.get("x", 0)) <= 1 and abs(g.y - s.get("y", 0)) <= 1, (what, g)
        assert g.param1 == pytest.approx(s.get("p1", 0.0)), (what, g)
        if what == "rally":
            assert g.z == pytest.approx(s["z"], abs=0.5), (what, g)


@pytest.mark.parametrize("kind", KINDS)
def test_plan_upload_download_bad_fence_and_clear(kind, tmp_path):
    ap = start(kind, tmp_path)
    g = None
    try:
        g = Gcs(ap.pymavlink_url)
        g.streams(5)
        pos = g.wait("GLOBAL_POSITION_INT", lambda p: p.lat != 0, 60.0)
        assert pos is not None
        mission, fence, rally = _plan(pos.lat / 1e7, pos.lon / 1e7)
        for mtype, items in ((MISSION, mission), (FENCE, fence), (RALLY, rally)):
            ack = g.upload(mtype, items)
            assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED, (mtype, ack)
        _same(fence, g.download(FENCE), "fence")
        _same(rally, g.download(RALLY), "rally")
        assert [i.command for i in g.download(MISSION)[1:]] == [it["command"]
                                                                 for it in mission[1:]]
        assert g.get_param("RALLY_TOTAL") == 2

        bad = [dict(it) for it in fence[:4]]
        bad[2]["p1"] = 5                       # the vertex count changes mid-polygon
        ack = g.upload(FENCE, bad)
        assert ack is not None and ack.type != mav.MAV_MISSION_ACCEPTED, ack
        _same(fence, g.download(FENCE), "fence after a bad upload")

        ack = g.clear(FENCE)
        assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED
        assert g.download(FENCE) == []
        _same(rally, g.download(RALLY), "rally after clearing the fence")
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if g is not None:
            g.close()
        ap.stop()


@pytest.mark.parametrize("kind", KINDS)
def test_home_position_on_request_and_at_arming_and_fence_prearm(kind, tmp_path):
    ap = start(kind, tmp_path)
    g = None
    try:
        g = Gcs(ap.pymavlink_url)
        g.streams(10)
        assert g.wait("GLOBAL_POSITION_INT", lambda p: p.lat != 0, 60.0) is not None
        g.pump(3.0)                     # home is set (and announced) by now
        t0 = time.monotonic()
        g.pump(4.0)
        n = g.count_since("HOME_POSITION", t0)
        assert n <= 1, f"{n} HOME_POSITION in 4 s nobody asked for"
        t0 = time.monotonic()
        ack = g.command(mav.MAV_CMD_GET_HOME_POSITION)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED
        assert g.wait_seen("HOME_POSITION", t0, 3.0), "no HOME_POSITION on request"

        # FENCE_ENABLE with only the polygon type and no fence uploaded: no arming
        assert g.set_param("FENCE_TYPE", 4) == 4
        assert g.set_param("FENCE_ENABLE", 1) == 1
        t0 = time.monotonic()
        g.command(mav.MAV_CMD_DO_SET_MODE, 1, 4)
        ack = g.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        assert ack is not None and ack.result != mav.MAV_RESULT_ACCEPTED
        g.pump(1.0)
        assert g.text_seen("Fences enabled, but none selected", t0), g.texts[-5:]

        # an exclusion circle around the vehicle: it is breaching the fence, no arming
        pos = g.last["GLOBAL_POSITION_INT"]
        ack = g.upload(FENCE, [dict(frame=G_INT, command=mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
                                    p1=20.0, x=pos.lat, y=pos.lon)])
        assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED
        g.pump(1.0)
        t0 = time.monotonic()
        ack = g.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        assert ack is not None and ack.result != mav.MAV_RESULT_ACCEPTED
        g.pump(1.0)
        assert g.text_seen("Vehicle breaching Polygon fence", t0), g.texts[-5:]
        assert not any("fence breached" in t for _, _, t in g.texts), "announced while disarmed"
        assert g.clear(FENCE).type == mav.MAV_MISSION_ACCEPTED
        assert g.set_param("FENCE_ENABLE", 0) == 0

        t0 = time.monotonic()
        g.arm_and_takeoff(5.0)
        assert g.wait_seen("HOME_POSITION", t0, 5.0), "no HOME_POSITION at arming"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if g is not None:
            g.close()
        ap.stop()
