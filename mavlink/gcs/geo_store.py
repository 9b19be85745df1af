"""Fence and rally items: the stores and their rules (mission types FENCE 1 and RALLY 2).

QGroundControl uploads a plan as three lists through the same MISSION_* protocol, told apart
by mission_type. Unlike the mission there is no home slot: item 0 is the first vertex or
rally point. What ArduCopter 4.6 accepts, and so do we:

* fence: MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION / _EXCLUSION (5001 / 5002, param1 = the
  polygon's vertex count, the same on each of its vertices, at least 3) and
  MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION / _EXCLUSION (5003 / 5004, param1 = radius in metres,
  > 0), in a global frame. A polygon's vertices are consecutive; a list that ends inside a
  polygon is refused at the end of the upload (MAV_MISSION_INVALID).
* rally: MAV_CMD_NAV_RALLY_POINT (5100) in a global frame; z is the altitude (relative to
  home in the relative frames, as QGC sends them).

A store is replaced whole or not at all (``replace`` checks the complete list first), so a
bad or abandoned upload leaves the previous fence or rally list untouched.
"""

from __future__ import annotations

import dataclasses
import math
import threading

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.mission_store import GLOBAL_FRAMES
from silbridge.mavlink.gcs.vehicle_api import MissionItem

FENCE_POLY = frozenset({mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                        mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION})
FENCE_CIRCLE = frozenset({mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
                          mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION})
FENCE_COMMANDS = FENCE_POLY | FENCE_CIRCLE
RALLY_COMMANDS = frozenset({mav.MAV_CMD_NAV_RALLY_POINT})
# Our limits (items held in memory): far above what a GCS plan holds.
FENCE_CAPACITY = 200
RALLY_CAPACITY = 100


def _check_position(item: MissionItem) -> int:
    if item.frame not in GLOBAL_FRAMES:
        return mav.MAV_MISSION_UNSUPPORTED_FRAME
    if not -900_000_000 <= item.x <= 900_000_000:
        return mav.MAV_MISSION_INVALID_PARAM5_X
    if not -1_800_000_000 <= item.y <= 1_800_000_000:
        return mav.MAV_MISSION_INVALID_PARAM6_Y
    return mav.MAV_MISSION_ACCEPTED


def check_fence_item(item: MissionItem, previous: list[MissionItem] | tuple = ()) -> int:
    """MAV_MISSION_ACCEPTED or why this fence item is refused, given the items before it."""
    if item.command not in FENCE_COMMANDS:
        return mav.MAV_MISSION_UNSUPPORTED
    result = _check_position(item)
    if result != mav.MAV_MISSION_ACCEPTED:
        return result
    if item.command in FENCE_CIRCLE:
        if not (math.isfinite(item.param1) and item.param1 > 0.0):
            return mav.MAV_MISSION_INVALID_PARAM1           # radius, m
        if _open_polygon(previous) is not None:
            return mav.MAV_MISSION_INVALID_SEQUENCE         # a polygon is not finished
        return mav.MAV_MISSION_ACCEPTED
    if not (math.isfinite(item.param1) and item.param1 >= 3 and item.param1 == int(item.param1)):
        return mav.MAV_MISSION_INVALID_PARAM1               # vertex count
    open_poly = _open_polygon(previous)
    if open_poly is not None and (open_poly[0] != item.command
                                  or open_poly[1] != int(item.param1)):
        return mav.MAV_MISSION_INVALID_PARAM1               # vertex count differs mid-polygon
    return mav.MAV_MISSION_ACCEPTED


def _open_polygon(items) -> tuple[int, int] | None:
    """(command, vertex count) of a polygon still missing vertices at the end of items."""
    i = 0
    n = len(items)
    while i < n:
        it = items[i]
        if it.command in FENCE_POLY:
            count = int(it.param1)
            if i + count > n:
                return it.command, count
            i += count
        else:
            i += 1
    return None


def check_rally_item(item: MissionItem, previous=()) -> int:
    if item.command not in RALLY_COMMANDS:
        return mav.MAV_MISSION_UNSUPPORTED
    result = _check_position(item)
    if result == mav.MAV_MISSION_ACCEPTED and not math.isfinite(item.z):
        return mav.MAV_MISSION_INVALID_PARAM7
    return result


def check_list(mission_type: int, items) -> tuple[int, int]:
    """(MAV_MISSION result, index of the first bad item or -1) for a whole fence/rally list."""
    check = check_fence_item if mission_type == mav.MAV_MISSION_TYPE_FENCE else check_rally_item
    for i, it in enumerate(items):
        if it.seq != i:
            return mav.MAV_MISSION_INVALID_SEQUENCE, i
        result = check(it, items[:i])
        if result != mav.MAV_MISSION_ACCEPTED:
            return result, i
    if mission_type == mav.MAV_MISSION_TYPE_FENCE and _open_polygon(items) is not None:
        return mav.MAV_MISSION_INVALID, len(items)
    return mav.MAV_MISSION_ACCEPTED, -1


class GeoStore:
    """Thread-safe holder of the fence or the rally list (a tuple; empty when cleared)."""

    def __init__(self, mission_type: int, capacity: int | None = None):
        if mission_type not in (mav.MAV_MISSION_TYPE_FENCE, mav.MAV_MISSION_TYPE_RALLY):
            raise ValueError(f"GeoStore holds fence (1) or rally (2) items, not {mission_type}")
        self.mission_type = mission_type
        self.capacity = capacity if capacity is not None else (
            FENCE_CAPACITY if mission_type == mav.MAV_MISSION_TYPE_FENCE else RALLY_CAPACITY)
        self._lock = threading.Lock()
        self._items: tuple[MissionItem, ...] = ()

    @property
    def what(self) -> str:
        return "Fence" if self.mission_type == mav.MAV_MISSION_TYPE_FENCE else "Rally"

    def check_item(self, item: MissionItem, previous) -> int:
        if self.mission_type == mav.MAV_MISSION_TYPE_FENCE:
            return check_fence_item(item, previous)
        return check_rally_item(item, previous)

    def items(self) -> tuple[MissionItem, ...]:
        return self._items

    def count(self) -> int:
        return len(self._items)

    def replace(self, items) -> int:
        items = tuple(items)
        if len(items) > self.capacity:
            return mav.MAV_MISSION_NO_SPACE
        result, _ = check_list(self.mission_type, items)
        if result != mav.MAV_MISSION_ACCEPTED:
            return result
        with self._lock:
            # read back as ArduCopter returns them: current 0, autocontinue 0
            self._items = tuple(dataclasses.replace(it, mission_type=self.mission_type,
                                                    current=0, autocontinue=0) for it in items)
        return mav.MAV_MISSION_ACCEPTED

    def clear(self) -> None:
        with self._lock:
            self._items = ()
