"""Which mission items an upload accepts (mission_store.py): the commands of missions' paths
(spline waypoints, loiter turns, NAV_DELAY, DO_JUMP, ROI, CONDITION_DELAY / _YAW) with
ArduCopter 4.6's answers, and a refused item leaves the stored mission as it was."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.mission_store import MissionStore, check_item, home_item
from silbridge.mavlink.gcs.vehicle_api import MissionItem

REL, MF = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_FRAME_MISSION
LAT, LON = -353632621, 1491652374
NAN = float("nan")


def _item(command, frame=REL, p=(0.0, 0.0, 0.0, 0.0), at=True, z=10.0, seq=1):
    x, y = (LAT, LON) if at else (0, 0)
    return MissionItem(seq, frame, command, 0, 1, *p, x, y, z)


PATH_ITEMS = [
    _item(mav.MAV_CMD_NAV_SPLINE_WAYPOINT),
    _item(mav.MAV_CMD_NAV_LOITER_TURNS, p=(2.0, 0.0, -10.0, 0.0)),
    _item(mav.MAV_CMD_NAV_DELAY, MF, p=(5.0, -1.0, -1.0, -1.0), at=False, z=0.0),
    _item(mav.MAV_CMD_DO_JUMP, MF, p=(1.0, -1.0, 0.0, 0.0), at=False, z=0.0),
    _item(mav.MAV_CMD_DO_SET_ROI, p=(3.0, 0.0, 0.0, 0.0)),
    _item(mav.MAV_CMD_DO_SET_ROI_LOCATION),
    _item(mav.MAV_CMD_DO_SET_ROI_NONE, MF, at=False, z=0.0),
    _item(mav.MAV_CMD_CONDITION_DELAY, MF, p=(3.0, 0.0, 0.0, 0.0), at=False, z=0.0),
    _item(mav.MAV_CMD_CONDITION_YAW, MF, p=(90.0, 20.0, 1.0, 0.0), at=False, z=0.0),
]


@pytest.mark.parametrize("item", PATH_ITEMS, ids=lambda it: str(it.command))
def test_path_commands_are_accepted(item):
    assert check_item(item) == mav.MAV_MISSION_ACCEPTED


def test_a_nan_parameter_is_refused_as_arducopter_refuses_it():
    for k, err in enumerate((mav.MAV_MISSION_INVALID_PARAM1, mav.MAV_MISSION_INVALID_PARAM2,
                             mav.MAV_MISSION_INVALID_PARAM3, mav.MAV_MISSION_INVALID_PARAM4)):
        p = [0.0, 0.0, 0.0, 0.0]
        p[k] = NAN
        assert check_item(_item(mav.MAV_CMD_NAV_SPLINE_WAYPOINT, p=tuple(p))) == err
    # a waypoint's yaw (param 4) may still be NaN, as QGroundControl and MAVSDK send it
    assert check_item(_item(mav.MAV_CMD_NAV_WAYPOINT, p=(0.0, 0.0, 0.0, NAN))) == \
        mav.MAV_MISSION_ACCEPTED


def test_positions_are_checked_and_need_a_global_frame():
    bad_lat = MissionItem(1, REL, mav.MAV_CMD_NAV_LOITER_TURNS, x=910_000_000, y=LON, z=10.0)
    assert check_item(bad_lat) == mav.MAV_MISSION_INVALID_PARAM5_X
    local = _item(mav.MAV_CMD_NAV_SPLINE_WAYPOINT, frame=mav.MAV_FRAME_LOCAL_NED)
    assert check_item(local) == mav.MAV_MISSION_UNSUPPORTED_FRAME


def test_a_refused_upload_leaves_the_mission_stored_before_it():
    store = MissionStore()
    good = [home_item(LAT, LON, 584.0)] + [
        MissionItem(i, it.frame, it.command, 0, 1, it.param1, it.param2, it.param3,
                    it.param4, it.x, it.y, it.z) for i, it in enumerate(PATH_ITEMS, 1)]
    assert store.replace(good) == mav.MAV_MISSION_ACCEPTED
    bad = list(good)
    bad[1] = MissionItem(1, REL, mav.MAV_CMD_NAV_SPLINE_WAYPOINT, 0, 1, 0.0, 0.0, 0.0, NAN,
                         LAT, LON, 10.0)
    assert store.replace(bad) == mav.MAV_MISSION_INVALID_PARAM4
    assert [it.command for it in store.items()] == [it.command for it in good]
    assert store.items()[1].param4 == 0.0
