"""DO and CONDITION commands in AUTO, flown in lockstep (vehicle_harness): they run beside the
next navigation command and report as ArduCopter 4.6 reports them.

The plan and the sequences below were recorded from ArduCopter 4.6.0 SITL flying it:
MISSION_CURRENT 1 2 6 8 10 11, and MISSION_ITEM_REACHED 1 3 4 5 7 9 10 11 (its item-reached
message is deferred: of a waypoint and the DO command completing with it only the DO's seq
goes out, so 2, 6 and 8 never appear). CONDITION_YAW 90 leaves it heading 89 deg.
"""

from __future__ import annotations

import math
import os
import sys

from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.mavlink.gcs.vehicle_api import CopterMode, MissionItem  # noqa: E402

REL, MF = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_FRAME_MISSION


def _plan(v):
    def at(n, e):
        return v.est.origin.to_latlon_e7(v.home_ne[0] + n, v.home_ne[1] + e)

    def wp(cmd, n, e, z=10.0, p=(0.0, 0.0, 0.0, 0.0)):
        return (REL, cmd, *p, *at(n, e), z)

    def nop(cmd, p=(0.0, 0.0, 0.0, 0.0)):
        return (MF, cmd, *p, 0, 0, 0.0)

    rows = [(REL, mav.MAV_CMD_NAV_TAKEOFF, 0.0, 0.0, 0.0, 0.0, 0, 0, 10.0),
            wp(mav.MAV_CMD_NAV_WAYPOINT, 20, 0, p=(3.0, 0.0, 0.0, 0.0)),       # 2: hold 3 s
            wp(mav.MAV_CMD_DO_SET_ROI_LOCATION, 0, 30, 0.0),                    # 3
            nop(mav.MAV_CMD_CONDITION_DELAY, (2.0, 0.0, 0.0, 0.0)),            # 4
            nop(mav.MAV_CMD_CONDITION_YAW, (90.0, 0.0, 0.0, 0.0)),             # 5
            wp(mav.MAV_CMD_NAV_WAYPOINT, 20, 20),                              # 6
            nop(mav.MAV_CMD_DO_SET_ROI_NONE),                                  # 7
            wp(mav.MAV_CMD_NAV_LOITER_TIME, 0, 20, p=(2.0, 0.0, 0.0, 0.0)),    # 8
            nop(mav.MAV_CMD_DO_CHANGE_SPEED, (1.0, 3.0, 0.0, 0.0)),            # 9
            wp(mav.MAV_CMD_NAV_DELAY, 0, 0, 0.0, (2.0, -1.0, -1.0, -1.0)),     # 10
            (REL, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0, 0.0, 0.0, 0.0, 0, 0, 0.0)]  # 11
    items = [MissionItem(0, mav.MAV_FRAME_GLOBAL, mav.MAV_CMD_NAV_WAYPOINT, x=v.home_lat_e7,
                         y=v.home_lon_e7, z=v.home_alt_msl_m)]
    for i, (fr, c, p1, p2, p3, p4, x, y, z) in enumerate(rows, 1):
        items.append(MissionItem(i, fr, c, 0, 1, p1, p2, p3, p4, x, y, z))
    return tuple(items)


def test_do_and_condition_commands_run_and_report_as_arducopter():
    st = {"current": [], "heading_at_8": None}

    def script(f):
        v, t = f.v, f.t_s
        if "r" not in st and t > 3:
            v.mission_updated(_plan(v))
            st["r"] = (v.set_mode(CopterMode.GUIDED), v.arm(False), v.mission_start(0, 0))
        if "r" in st:
            cur = v.mission.current
            if not st["current"] or st["current"][-1] != cur:
                st["current"].append(cur)
                if cur == 8:
                    st["heading_at_8"] = math.degrees(v.yaw_rad)
                    st["speed_at_8"] = v.speed_override_m_s
        if "r" in st and not v.armed and t > 10:
            f.stop_requested = True

    f, res = fly_scripted(script, duration_s=150)
    assert all(r[0] == mav.MAV_RESULT_ACCEPTED for r in st["r"]), st["r"]
    assert not res.crashed
    assert st["current"][:6] == [1, 2, 6, 8, 10, 11], st["current"]
    reached = [int(m[2].split("#")[1]) for m in f.v.messages if m[2].startswith("Reached")]
    assert reached == [1, 3, 4, 5, 7, 9, 10, 11]
    texts = [m[2] for m in f.v.messages]
    started = [t for t in texts if t.startswith("Mission: ")]
    # the ROI and the next waypoint start together, the DOs after it one by one
    assert started[:6] == ["Mission: 1 Takeoff", "Mission: 2 WP", "Mission: 3 SetROILocation",
                           "Mission: 6 WP", "Mission: 4 CondDelay", "Mission: 5 CondYaw"]
    assert "Delaying 2 sec" in texts
    # CONDITION_YAW 90 held the nose through WP 6 (the ROI would point it at 124 deg)
    assert abs(st["heading_at_8"] - 90.0) < 10.0, st["heading_at_8"]
    assert st["speed_at_8"] is None, "DO_CHANGE_SPEED 9 runs beside item 10, after 8"
    assert not f.v.armed and f.v.mission.state == mav.MISSION_STATE_COMPLETE
