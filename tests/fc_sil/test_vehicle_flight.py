"""The MAVLink vehicle flies: real JSBSim physics, real shared memory, the C core, lockstep.

Commands are issued the way GcsServer.service() issues them (on the vehicle thread, between
batches). Assertions use the simulator's truth, with bounds that allow for the GNSS error
the position estimate inherits (the scenario's receiver has 2.1 m horizontal sigma).
"""

from __future__ import annotations

import math
import os
import sys

from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.mavlink.gcs.vehicle_api import CopterMode, MissionItem  # noqa: E402

ACCEPTED = mav.MAV_RESULT_ACCEPTED


def _once(state: dict, key: str, cond: bool) -> bool:
    if cond and key not in state:
        state[key] = True
        return True
    return False


def _guided_takeoff(v, alt_m: float) -> tuple:
    """GUIDED, arm, take off to alt_m: the three replies."""
    return (v.set_mode(CopterMode.GUIDED), v.arm(False), v.takeoff(alt_m))


def _mission(v, legs_ne, alt_m=10.0, rtl=True):
    o = v.est.origin
    items = [MissionItem(0, mav.MAV_FRAME_GLOBAL, mav.MAV_CMD_NAV_WAYPOINT, x=v.home_lat_e7,
                         y=v.home_lon_e7, z=v.home_alt_msl_m),
             MissionItem(1, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_CMD_NAV_TAKEOFF,
                         current=1, z=alt_m)]
    for n, e in legs_ne:
        lat, lon = o.to_latlon_e7(n, e)
        items.append(MissionItem(len(items), mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                                 mav.MAV_CMD_NAV_WAYPOINT, x=lat, y=lon, z=alt_m))
    if rtl:
        items.append(MissionItem(len(items), mav.MAV_FRAME_MISSION,
                                 mav.MAV_CMD_NAV_RETURN_TO_LAUNCH))
    return tuple(items)


def test_guided_takeoff_hold_reposition_land_disarm():
    st, replies, hold = {}, [], []

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "up", t > 3):
            replies.extend(_guided_takeoff(v, 10.0))
        if 14 < t < 18:
            hold.append((f.truth_agl_m(), f.truth_tilt_deg()))
        if _once(st, "go", t > 18):
            lat, lon = v.est.origin.to_latlon_e7(v.home_ne[0] + 30.0, v.home_ne[1] - 20.0)
            replies.append(v.reposition(lat, lon, 12.0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                                        float("nan"), float("nan")))
        if _once(st, "at", t > 36):
            st["ne_at_goto"] = f.truth_ne_m()
            st["agl_at_goto"] = f.truth_agl_m()
            replies.append(v.land())

    f, res = fly_scripted(script, duration_s=70)
    assert [r[0] for r in replies] == [ACCEPTED] * 5, replies
    assert not res.crashed
    agl = [a for a, _ in hold]
    assert min(agl) > 9.0 and max(agl) < 11.0, (min(agl), max(agl))
    assert max(t for _, t in hold) < 8.0
    n, e = st["ne_at_goto"]
    # 30 m north, 20 m west of home, within the GNSS error of the estimate
    assert math.hypot(n - 30.0, e + 20.0) < 5.0, (n, e)
    assert abs(st["agl_at_goto"] - 12.0) < 1.0
    assert not f.v.armed, "LAND disarms on touchdown"
    assert f.truth_agl_m() < 0.2
    assert any("landed, disarming" in m[2] for m in f.v.messages)


def test_auto_mission_takeoff_three_waypoints_rtl():
    st = {}
    legs = [(25.0, 0.0), (25.0, 25.0), (0.0, 25.0)]

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "up", t > 3):
            v.mission_updated(_mission(v, legs))
            st["r"] = (v.set_mode(CopterMode.GUIDED), v.arm(False), v.set_mode(CopterMode.AUTO))
        seq = v.mission.current
        if v.mission.item_state == "go" and 2 <= seq <= 4:
            st.setdefault("max_agl", 0.0)
            st["max_agl"] = max(st["max_agl"], f.truth_agl_m())
        if v.mission.state == mav.MISSION_STATE_COMPLETE:
            st.setdefault("done_t", t)

    f, res = fly_scripted(script, duration_s=95)
    assert all(r[0] == ACCEPTED for r in st["r"]), st["r"]
    assert not res.crashed
    reached = [int(m[2].split("#")[1]) for m in f.v.messages if m[2].startswith("Reached")]
    assert reached == [1, 2, 3, 4, 5]
    assert f.v.mission.state == mav.MISSION_STATE_COMPLETE
    assert not f.v.armed
    n, e = f.truth_ne_m()
    assert math.hypot(n, e) < 5.0, "RTL lands at home"
    assert st["max_agl"] < 12.0


def test_auto_refuses_without_takeoff_item_when_landed():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "go", t > 3):
            items = _mission(v, [(10.0, 0.0)])
            items = (items[0],) + tuple(
                MissionItem(i, it.frame, it.command, it.current, it.autocontinue, it.param1,
                            it.param2, it.param3, it.param4, it.x, it.y, it.z)
                for i, it in enumerate(items[2:], 1))
            v.mission_updated(items)
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            st["auto"] = v.set_mode(CopterMode.AUTO)
            st["mode"] = v.mode.number

    fly_scripted(script, duration_s=4)
    assert st["auto"] == (mav.MAV_RESULT_FAILED, "Auto: Missing Takeoff Cmd")
    assert st["mode"] == CopterMode.GUIDED


def test_rtl_from_away_climbs_to_rtl_alt_and_lands_home():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "up", t > 3):
            _guided_takeoff(v, 6.0)
        if _once(st, "go", t > 12):
            lat, lon = v.est.origin.to_latlon_e7(v.home_ne[0] - 25.0, v.home_ne[1])
            v.reposition(lat, lon, 6.0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, float("nan"),
                         float("nan"))
        if _once(st, "rtl", t > 24):
            st["r"] = v.rtl()
        if "rtl" in st and v.armed:
            st["max_agl"] = max(st.get("max_agl", 0.0), f.truth_agl_m())

    f, res = fly_scripted(script, duration_s=75, params={"RTL_ALT": 1200, "RTL_LOIT_TIME": 1000})
    assert st["r"] == (ACCEPTED, None)
    assert not res.crashed
    assert 11.0 < st["max_agl"] < 13.5, st["max_agl"]
    assert not f.v.armed
    assert math.hypot(*f.truth_ne_m()) < 5.0


def test_alt_hold_follows_the_throttle_stick_and_holds_when_centred():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "arm", t > 3):
            v.set_mode(CopterMode.ALT_HOLD)
            v.manual_control(0, 0, 500, 0, 0)
            st["arm"] = v.arm(False)
        if 3.5 < t < 9:
            v.manual_control(0, 0, 900, 0, 0)        # climb at (0.9 - 0.6) / 0.4 of 2.5 m/s
        elif t >= 9:
            v.manual_control(0, 0, 500, 0, 0)        # centred: hold
        if _once(st, "a", t > 12):
            st["agl12"] = f.truth_agl_m()
        if _once(st, "b", t > 20):
            st["agl20"] = f.truth_agl_m()

    f, res = fly_scripted(script, duration_s=21)
    assert st["arm"] == (ACCEPTED, None)
    assert st["agl12"] > 5.0
    assert abs(st["agl20"] - st["agl12"]) < 0.8


def test_guided_velocity_target_stops_after_guid_timeout():
    from silbridge.mavlink.gcs.vehicle_api import PositionTarget

    st = {}

    def vel_target(vn):
        return PositionTarget(0, mav.MAV_FRAME_LOCAL_NED, 0b110111000111, False, 0.0, 0.0, 0.0,
                              (vn, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.0, 255)

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "up", t > 3):
            _guided_takeoff(v, 8.0)
        if 12 < t < 16:
            v.set_position_target(vel_target(3.0))   # streamed, as offboard scripts do
        if _once(st, "a", t > 15.5):
            st["v_during"] = v.est.vel_ne_m_s[0]
        if _once(st, "b", t > 24):
            st["v_after"] = math.hypot(*v.est.vel_ne_m_s)

    fly_scripted(script, duration_s=25, params={"GUID_TIMEOUT": 2.0})
    assert 2.0 < st["v_during"] < 4.0
    assert st["v_after"] < 0.6


def test_loiter_sticks_move_then_brake_stops_and_holds():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "up", t > 3):
            _guided_takeoff(v, 8.0)
        if _once(st, "loiter", t > 12):
            st["r_loiter"] = v.set_mode(CopterMode.LOITER)
            st["ne0"] = f.truth_ne_m()
        if 12 < t < 18:
            v.manual_control(600, 0, 500, 0, 0)        # stick 60 % forward, facing north
        if _once(st, "brake", t > 18):
            st["v_fwd"] = v.est.vel_ne_m_s[0]
            st["r_brake"] = v.set_mode(CopterMode.BRAKE)
        if t > 18:
            v.manual_control(0, 0, 500, 0, 0)
        if _once(st, "held", t > 24):
            st["ne_a"] = f.truth_ne_m()
        if _once(st, "end", t > 29):
            st["ne_b"] = f.truth_ne_m()
            st["agl"] = f.truth_agl_m()

    f, res = fly_scripted(script, duration_s=30)
    assert st["r_loiter"] == (ACCEPTED, None) and st["r_brake"] == (ACCEPTED, None)
    assert st["v_fwd"] > 3.0
    moved = math.hypot(st["ne_a"][0] - st["ne0"][0], st["ne_a"][1] - st["ne0"][1])
    assert moved > 15.0
    drift = math.hypot(st["ne_b"][0] - st["ne_a"][0], st["ne_b"][1] - st["ne_a"][1])
    assert drift < 2.5, "BRAKE holds where it stopped"
    assert abs(st["agl"] - 8.0) < 1.0
    assert not res.crashed


def test_stabilize_manual_throttle_and_global_int_target_in_guided():
    from silbridge.mavlink.gcs.vehicle_api import PositionTarget

    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if _once(st, "arm", t > 3):
            v.set_mode(CopterMode.STABILIZE)
            v.manual_control(0, 0, 0, 0, 0)
            st["arm"] = v.arm(False)
        if 3.2 < t < 8:
            v.manual_control(0, 0, 700, 0, 0)          # above hover: climbs
        if _once(st, "climbed", t > 8):
            st["agl8"] = f.truth_agl_m()
            st["guided"] = v.set_mode(CopterMode.GUIDED)
            lat, lon = v.est.origin.to_latlon_e7(v.home_ne[0] + 15.0, v.home_ne[1] + 10.0)
            v.set_position_target(PositionTarget(
                0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0b110111111000, True, lat, lon, 9.0,
                (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.0, 255))
        if _once(st, "there", t > 22):
            st["ne"] = f.truth_ne_m()
            st["agl"] = f.truth_agl_m()

    f, res = fly_scripted(script, duration_s=23)
    assert st["arm"] == (ACCEPTED, None) and st["guided"] == (ACCEPTED, None)
    assert st["agl8"] > 2.0
    assert math.hypot(st["ne"][0] - 15.0, st["ne"][1] - 10.0) < 5.0
    assert abs(st["agl"] - 9.0) < 1.0
    assert not res.crashed
