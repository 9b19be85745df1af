"""The stored mission: home at seq 0, replaced whole or not at all, and the item rules.

ArduPilot conventions: item 0 is the home slot (stored, never flown); an empty mission still
holds it, so a download always returns at least one item. A new mission is checked item by
item while it arrives and becomes visible only once complete (``replace``), so a failed or
abandoned upload leaves the previous mission untouched.

What we fly (fc_sil/mission_exec.py): NAV_WAYPOINT, NAV_SPLINE_WAYPOINT, NAV_TAKEOFF, NAV_LAND,
NAV_RETURN_TO_LAUNCH, NAV_LOITER_TIME, NAV_LOITER_TURNS, NAV_DELAY, DO_JUMP, DO_CHANGE_SPEED,
DO_SET_ROI, DO_SET_ROI_LOCATION, DO_SET_ROI_NONE, CONDITION_DELAY and CONDITION_YAW, in the
global frames (absolute or relative altitude, float or _INT form). Commands without a position
may also use MAV_FRAME_MISSION, as QGC sends them. The commands added for missions' paths take
ArduCopter's parameter rule: a NaN parameter is refused (MAV_MISSION_INVALID_PARAMn); a DO_JUMP
to an item that does not exist is accepted, as ArduCopter does, and ends the mission when taken.
"""

from __future__ import annotations

import dataclasses
import math
import threading

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import MissionItem

# the commands of missions' paths, with ArduCopter's rule that no parameter may be NaN
PATH_COMMANDS = frozenset({
    mav.MAV_CMD_NAV_SPLINE_WAYPOINT, mav.MAV_CMD_NAV_LOITER_TURNS, mav.MAV_CMD_NAV_DELAY,
    mav.MAV_CMD_DO_JUMP, mav.MAV_CMD_DO_SET_ROI, mav.MAV_CMD_DO_SET_ROI_LOCATION,
    mav.MAV_CMD_DO_SET_ROI_NONE, mav.MAV_CMD_CONDITION_DELAY, mav.MAV_CMD_CONDITION_YAW,
})
SUPPORTED_COMMANDS = frozenset({
    mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_TAKEOFF, mav.MAV_CMD_NAV_LAND,
    mav.MAV_CMD_NAV_RETURN_TO_LAUNCH, mav.MAV_CMD_NAV_LOITER_TIME, mav.MAV_CMD_DO_CHANGE_SPEED,
}) | PATH_COMMANDS
NAV_COMMANDS = frozenset(c for c in SUPPORTED_COMMANDS if c <= mav.MAV_CMD_NAV_LAST)
POSITION_COMMANDS = frozenset({mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_TAKEOFF,
                               mav.MAV_CMD_NAV_LAND, mav.MAV_CMD_NAV_LOITER_TIME,
                               mav.MAV_CMD_NAV_SPLINE_WAYPOINT, mav.MAV_CMD_NAV_LOITER_TURNS,
                               mav.MAV_CMD_DO_SET_ROI, mav.MAV_CMD_DO_SET_ROI_LOCATION})
GLOBAL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                           mav.MAV_FRAME_GLOBAL_INT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})
NO_POSITION_FRAMES = GLOBAL_FRAMES | {mav.MAV_FRAME_MISSION}
DEFAULT_CAPACITY = 700     # items, like a 4.5 ArduCopter on a board with a small storage area

_PARAM_ERRORS = (mav.MAV_MISSION_INVALID_PARAM1, mav.MAV_MISSION_INVALID_PARAM2,
                 mav.MAV_MISSION_INVALID_PARAM3, mav.MAV_MISSION_INVALID_PARAM4)


def home_item(lat_e7: int = 0, lon_e7: int = 0, alt_msl_m: float = 0.0) -> MissionItem:
    return MissionItem(seq=0, frame=mav.MAV_FRAME_GLOBAL, command=mav.MAV_CMD_NAV_WAYPOINT,
                       current=0, autocontinue=1, x=lat_e7, y=lon_e7, z=alt_msl_m)


def check_item(item: MissionItem) -> int:
    """MAV_MISSION_ACCEPTED or the precise MAV_MISSION_* reason the item is refused."""
    if item.command not in SUPPORTED_COMMANDS:
        return mav.MAV_MISSION_UNSUPPORTED
    if item.frame not in (GLOBAL_FRAMES if item.command in POSITION_COMMANDS
                          else NO_POSITION_FRAMES):
        return mav.MAV_MISSION_UNSUPPORTED_FRAME
    params = (item.param1, item.param2, item.param3, item.param4)
    for k, p in enumerate(params):
        # NaN is MAVLink's "use the default / keep"; infinity is never meaningful.
        if math.isinf(p) or (math.isnan(p) and item.command in PATH_COMMANDS):
            return _PARAM_ERRORS[k]
    if item.command == mav.MAV_CMD_NAV_LOITER_TIME and not (item.param1 >= 0.0):
        return mav.MAV_MISSION_INVALID_PARAM1        # loiter time, s
    if item.command == mav.MAV_CMD_DO_CHANGE_SPEED and not math.isfinite(item.param2):
        return mav.MAV_MISSION_INVALID_PARAM2        # speed, m/s (-1: no change)
    if item.command in POSITION_COMMANDS:
        if not -900_000_000 <= item.x <= 900_000_000:
            return mav.MAV_MISSION_INVALID_PARAM5_X
        if not -1_800_000_000 <= item.y <= 1_800_000_000:
            return mav.MAV_MISSION_INVALID_PARAM6_Y
        if not math.isfinite(item.z):
            return mav.MAV_MISSION_INVALID_PARAM7
    return mav.MAV_MISSION_ACCEPTED


def check_mission(items: list[MissionItem] | tuple[MissionItem, ...]) -> tuple[int, int]:
    """(MAV_MISSION result, seq of the first bad item or -1)."""
    for i, item in enumerate(items):
        if item.seq != i:
            return mav.MAV_MISSION_INVALID_SEQUENCE, i
        result = check_item(item)
        if result != mav.MAV_MISSION_ACCEPTED:
            return result, i
    return mav.MAV_MISSION_ACCEPTED, -1


class MissionStore:
    """Thread-safe holder of the current mission (a tuple, home at index 0)."""

    def __init__(self, capacity: int = DEFAULT_CAPACITY):
        self.capacity = capacity
        self._lock = threading.Lock()
        self._items: tuple[MissionItem, ...] = (home_item(),)

    def items(self) -> tuple[MissionItem, ...]:
        return self._items

    def count(self) -> int:
        return len(self._items)

    def replace(self, items: list[MissionItem] | tuple[MissionItem, ...]) -> int:
        """Install a whole mission; return MAV_MISSION_ACCEPTED or why it was refused."""
        items = tuple(items) if items else (home_item(),)
        if len(items) > self.capacity:
            return mav.MAV_MISSION_NO_SPACE
        result, _ = check_mission(items)
        if result != mav.MAV_MISSION_ACCEPTED:
            return result
        with self._lock:
            self._items = tuple(dataclasses.replace(it, mission_type=mav.MAV_MISSION_TYPE_MISSION)
                                for it in items)
        return mav.MAV_MISSION_ACCEPTED

    def clear(self) -> None:
        with self._lock:
            self._items = (self._items[0],)
