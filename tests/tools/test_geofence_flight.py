"""Fly into each fence type and check what the autopilot does, on silbridge and (when
SILBRIDGE_ARDUCOPTER is set) on the real ArduCopter 4.6 SITL, driven identically by a pymavlink
ground station: FENCE_* parameters set over PARAM_SET, polygons uploaded as mission type FENCE,
GUIDED take-off, then velocity setpoints toward the fence.

Each case asserts the announced breach ("<type> fence breached"), the action's mode (FENCE_ACTION
1 RTL, 2 LAND, 4 BRAKE), FENCE_STATUS (breach_status 1 and the breach type: 2 max altitude,
3 boundary) and the SYS_STATUS geofence bit (present and enabled, unhealthy while breached).
ArduCopter's fence avoidance (AVOID_ENABLE, which slows the vehicle before a fence) is turned
off there: silbridge does not implement avoidance, and the point is the breach itself.
"""

from __future__ import annotations

import os
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, start  # noqa: E402
from gcs_session import BRAKE, LAND, RTL, Gcs, offset_e7  # noqa: E402

GEOFENCE = mav.MAV_SYS_STATUS_GEOFENCE
INCL, EXCL = (mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
              mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION)

CASES = {
    # name: (params, polygon (command, [(north, east)...]) or None, take-off m, (vn, ve),
    #        text, action mode, FENCE_STATUS breach_type)
    "alt_max": ({"FENCE_TYPE": 1, "FENCE_ALT_MAX": 12, "FENCE_ACTION": 2}, None, 20.0, None,
                "Max Alt fence breached", LAND, mav.FENCE_BREACH_MAXALT),
    "circle": ({"FENCE_TYPE": 2, "FENCE_RADIUS": 30, "FENCE_ACTION": 1}, None, 8.0, (5.0, 0.0),
               "Circle fence breached", RTL, mav.FENCE_BREACH_BOUNDARY),
    "polygon_inclusion": ({"FENCE_TYPE": 4, "FENCE_ACTION": 1},
                          (INCL, [(-25, -25), (25, -25), (25, 25), (-25, 25)]), 8.0, (0.0, 5.0),
                          "Polygon fence breached", RTL, mav.FENCE_BREACH_BOUNDARY),
    "polygon_exclusion": ({"FENCE_TYPE": 4, "FENCE_ACTION": 4},
                          (EXCL, [(15, -10), (40, -10), (40, 10), (15, 10)]), 8.0, (5.0, 0.0),
                          "Polygon fence breached", BRAKE, mav.FENCE_BREACH_BOUNDARY),
}


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("kind", KINDS)
def test_fly_into_fence(kind, case, tmp_path):
    params, polygon, alt, vel, text, action_mode, breach_type = CASES[case]
    ap = start(kind, tmp_path, arducopter_params={"AVOID_ENABLE": 0})
    g = None
    try:
        g = Gcs(ap.pymavlink_url)
        g.streams(10)
        pos = g.wait("GLOBAL_POSITION_INT", lambda p: p.lat != 0, 60.0)
        assert pos is not None, "no position"
        for name, value in {"FENCE_ENABLE": 1, **params}.items():
            assert g.set_param(name, value) == pytest.approx(value)
        if polygon is not None:
            cmd, pts = polygon
            items = []
            for n, e in pts:
                lat, lon = offset_e7(pos.lat / 1e7, pos.lon / 1e7, n, e)
                items.append(dict(frame=mav.MAV_FRAME_GLOBAL_INT, command=cmd, p1=len(pts),
                                  x=lat, y=lon))
            ack = g.upload(mav.MAV_MISSION_TYPE_FENCE, items)
            assert ack is not None and ack.type == mav.MAV_MISSION_ACCEPTED, ack
        st = g.wait("SYS_STATUS", lambda s: s.onboard_control_sensors_enabled & GEOFENCE, 10.0)
        assert st is not None, "the fence never showed as enabled in SYS_STATUS"
        assert st.onboard_control_sensors_present & GEOFENCE
        assert st.onboard_control_sensors_health & GEOFENCE
        g.arm_and_takeoff(alt)
        if vel is not None:
            assert g.wait_alt(alt - 1.5, 60.0), "take-off did not reach its altitude"
            g.fly_velocity(*vel, 40.0, stop=lambda: g.text_seen("fence breached"))
        assert g.text_seen("fence breached") or g.wait(
            "STATUSTEXT", lambda t: "fence breached" in t.text, 60.0) is not None, \
            f"no breach announced: {g.texts[-8:]}"
        assert g.text_seen(text), f"expected {text!r}: {g.texts[-8:]}"
        assert g.wait_mode(action_mode, 20.0), \
            f"mode {g.mode()} after the breach, expected {action_mode}: {g.texts[-8:]}"
        g.pump(1.0)
        assert breach_type in g.breach_types, f"FENCE_STATUS breach types {g.breach_types}"
        assert g.fence_unhealthy, "SYS_STATUS never showed the geofence unhealthy"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if g is not None:
            g.close()
        ap.stop()
