"""The mission cursor (mission_seq.py): DO_JUMP counts, look-ahead, DO commands beside
navigation, as ArduCopter 4.6 orders them (the sequences were recorded from its SITL)."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.mission_seq import MissionCursor
from silbridge.mavlink.gcs.vehicle_api import MissionItem

WP, SPLINE, TURNS, RTL = (mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_SPLINE_WAYPOINT,
                          mav.MAV_CMD_NAV_LOITER_TURNS, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH)
TAKEOFF, DELAY, JUMP = mav.MAV_CMD_NAV_TAKEOFF, mav.MAV_CMD_NAV_DELAY, mav.MAV_CMD_DO_JUMP
ROI, COND_DELAY, COND_YAW = (mav.MAV_CMD_DO_SET_ROI_LOCATION, mav.MAV_CMD_CONDITION_DELAY,
                             mav.MAV_CMD_CONDITION_YAW)


def _items(*cmds):
    out = [MissionItem(0, 0, WP)]
    for i, c in enumerate(cmds, 1):
        c, p1, p2 = (c + (0, 0))[:3] if isinstance(c, tuple) else (c, 0, 0)
        out.append(MissionItem(i, 0, c, param1=p1, param2=p2))
    return tuple(out)


def _navs(cur: MissionCursor, limit: int = 50) -> list[int]:
    seq = []
    nav, _ = cur.advance_nav(1)
    while nav is not None and len(seq) < limit:
        seq.append(nav)
        nav, _ = cur.advance_nav()
    return seq


def test_jump_once_repeats_its_target_then_goes_on():
    # take-off, WP, spline, spline, loiter turns, jump to 3 once, RTL (the test_mission_paths plan)
    cur = MissionCursor(_items(TAKEOFF, WP, SPLINE, SPLINE, TURNS, (JUMP, 3, 1), RTL))
    assert _navs(cur) == [1, 2, 3, 4, 5, 3, 4, 5, 7]
    assert cur.texts == ["Mission: 6 Jump 1/1"]


def test_jump_forever_never_ends_and_a_bad_target_ends_the_mission():
    cur = MissionCursor(_items(TAKEOFF, WP, (JUMP, 2, -1), RTL))
    assert _navs(cur, 9) == [1, 2, 2, 2, 2, 2, 2, 2, 2]
    cur = MissionCursor(_items(TAKEOFF, WP, (JUMP, 9, 1), RTL))
    assert _navs(cur) == [1, 2]
    cur = MissionCursor(_items(TAKEOFF, WP, (JUMP, 0, 1), RTL))
    assert _navs(cur) == [1, 2]


def test_two_jumps_nest():
    cur = MissionCursor(_items(TAKEOFF, WP, (JUMP, 2, 2), WP, (JUMP, 2, 1), RTL))
    # 2 (jump 3 twice) 2 2 4 (jump 5 once) 2 4 6; inner counts are not reset by the outer
    assert _navs(cur) == [1, 2, 2, 2, 4, 2, 4, 6]


def test_look_ahead_follows_a_jump_without_using_it():
    cur = MissionCursor(_items(TAKEOFF, SPLINE, (JUMP, 2, 1), RTL))
    assert cur.next_nav(3) == 2          # the loop back is still to come
    assert cur.next_nav(3) == 2          # ... and looking did not use it up
    assert cur.jumps_run == {}


def test_do_commands_run_beside_the_next_navigation_command():
    # recorded from ArduCopter 4.6: WP 2 completes -> ROI 3 and WP 6 start together; the
    # condition delay 4 then holds back the yaw 5; the DOs stop at the next nav command
    cur = MissionCursor(_items(TAKEOFF, (WP, 3), ROI, (COND_DELAY, 2), COND_YAW, WP, RTL))
    assert cur.advance_nav(1) == (1, None)
    assert cur.advance_do() is None               # no DO command before WP 2
    assert cur.advance_nav() == (2, None)
    assert cur.advance_nav() == (6, 3)
    assert cur.do_loaded and cur.do_index == 3
    cur.do_loaded = False                         # ROI done
    assert cur.advance_do() == 4
    cur.do_loaded = False
    assert cur.advance_do() == 5
    cur.do_loaded = False
    assert cur.advance_do() is None and cur.do_all_done
    assert cur.advance_nav() == (7, None)


def test_a_takeoff_must_come_first_but_a_nav_delay_may_precede_it():
    assert MissionCursor(_items(DELAY, TAKEOFF, WP)).starts_with_takeoff(1)
    assert not MissionCursor(_items(WP, TAKEOFF)).starts_with_takeoff(1)
    assert MissionCursor(_items((COND_DELAY, 1), TAKEOFF)).starts_with_takeoff(1)
