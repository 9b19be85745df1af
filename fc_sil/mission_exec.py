"""Mission execution for AUTO: the items of the MissionStore (home at seq 0), one at a time.

Supported (mavlink/gcs/mission_store.py accepts exactly these): NAV_TAKEOFF (z = altitude),
NAV_WAYPOINT (p1 = hold time s; lat/lon 0 = here), NAV_LOITER_TIME (p1 = time s),
NAV_LAND (lat/lon 0 = here), NAV_RETURN_TO_LAUNCH, DO_CHANGE_SPEED (p2 = m/s, -1 = keep).
Altitudes: relative frames above home, absolute frames above mean sea level (home altitude
subtracted), terrain frames as relative (we have no terrain data).

As ArduCopter: starting AUTO while armed and landed needs a TAKEOFF as the first nav item
("Missing Takeoff Cmd"); MISSION_ITEM_REACHED goes out for every nav item reached (take-off,
waypoints, the RTL and LAND items at touchdown); MISSION_CURRENT reports the item in
progress with mission_state ACTIVE, PAUSED (AUTO left), COMPLETE after the last item.
After the last item the vehicle holds position where it is (or stays landed).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .modes import RtlSequence

REL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                        mav.MAV_FRAME_GLOBAL_TERRAIN_ALT, mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})
NAV_COMMANDS = frozenset({mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_TAKEOFF,
                          mav.MAV_CMD_NAV_LAND, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH,
                          mav.MAV_CMD_NAV_LOITER_TIME})


class MissionExecutor:
    def __init__(self):
        self.items: tuple = ()
        self.current = 0                 # seq of the item in progress (0: not started)
        self.state = mav.MISSION_STATE_NOT_STARTED
        self.item_state = None           # per-item progress (see _begin)
        self.hold_until_ns = None
        self.rtl: RtlSequence | None = None
        self.hold_ne = None

    # ---- from the GCS -----------------------------------------------------------------------

    def set_items(self, items, v) -> None:
        """A new mission; a running one restarts at item 1 the next time AUTO starts."""
        self.items = tuple(items)
        self.current = 0
        self.state = (mav.MISSION_STATE_NOT_STARTED if len(self.items) > 1
                      else mav.MISSION_STATE_NO_MISSION)
        if v.mode.number == CopterMode.AUTO:
            v.statustext(mav.MAV_SEVERITY_WARNING, "Mission changed while in AUTO: holding")
            v.set_mode_internal(CopterMode.LOITER if v.position_ok()
                                else CopterMode.LAND, "mission changed")

    def set_current(self, seq: int, v) -> str | None:
        if not 0 < seq < len(self.items):
            return f"Mission has no item {seq}"
        self.current = seq
        if v.mode.number == CopterMode.AUTO:
            self._begin(v)
        return None

    def count(self) -> int:
        return max(0, len(self.items) - 1)

    def first_nav(self, start: int = 1):
        for it in self.items[start:]:
            if it.command in NAV_COMMANDS:
                return it
        return None

    # ---- mode hooks -------------------------------------------------------------------------

    def start(self, v, first: int | None = None) -> str | None:
        if len(self.items) <= 1:
            return "Mission: no mission loaded"
        if not v.position_ok():
            return "AUTO: need a position estimate (GPS)"
        if first is not None and 0 < first < len(self.items):
            self.current = first
        elif self.current <= 0 or self.current >= len(self.items) \
                or self.state == mav.MISSION_STATE_COMPLETE:
            self.current = 1
        if v.armed and not v.airborne:
            nav = self.first_nav(self.current)
            if nav is None or nav.command != mav.MAV_CMD_NAV_TAKEOFF:
                return "Auto: Missing Takeoff Cmd"
        self.state = mav.MISSION_STATE_ACTIVE
        self._begin(v)
        return None

    def pause(self, v) -> None:
        if self.state == mav.MISSION_STATE_ACTIVE:
            self.state = mav.MISSION_STATE_PAUSED
        v.takeoff_in_progress = False

    # ---- execution --------------------------------------------------------------------------

    def _alt_m(self, it, v) -> float:
        if it.frame in REL_FRAMES:
            return v.alt_from_home(float(it.z))
        return v.alt_from_msl(float(it.z))

    def _dest_ne(self, it, v):
        if it.x == 0 and it.y == 0:
            return tuple(v.est.pos_ne_m)
        return v.est.origin.to_ne(it.x, it.y)

    def _begin(self, v) -> None:
        """Start the item at self.current (DO items run at once and advance)."""
        while 0 < self.current < len(self.items):
            it = self.items[self.current]
            if it.command == mav.MAV_CMD_DO_CHANGE_SPEED:
                if math.isfinite(it.param2) and it.param2 > 0:
                    v.speed_override_m_s = float(it.param2)
                self.current += 1
                continue
            break
        if self.current >= len(self.items):
            self._complete(v)
            return
        it = self.items[self.current]
        self.hold_until_ns = None
        self.rtl = None
        self.item_state = "go"
        c = it.command
        if c == mav.MAV_CMD_NAV_TAKEOFF:
            self.item_state = "takeoff"
            self.takeoff_alt_m = max(self._alt_m(it, v), v.cfg.takeoff_min_m)
            self.hold_ne = tuple(v.est.pos_ne_m)
            if v.airborne and v.alt_m >= self.takeoff_alt_m - v.cfg.takeoff_done_m:
                self._reached(v)        # already up there: ArduCopter skips the climb
                return
            v.takeoff_in_progress = True
        elif c in (mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_LOITER_TIME):
            v.start_track(self._dest_ne(it, v), self._alt_m(it, v), v.speed_override_m_s)
            v.face_track(rtl=False)
        elif c == mav.MAV_CMD_NAV_LAND:
            dest = self._dest_ne(it, v)
            v.start_track(dest, v.alt_m, v.speed_override_m_s)
            self.hold_ne = dest
            self.item_state = "land_approach"
        elif c == mav.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            self.rtl = RtlSequence(v)
            self.item_state = "rtl"

    def run(self, v, dt_s: float) -> None:
        if self.state != mav.MISSION_STATE_ACTIVE:
            # complete (or no mission): hold where we are, or stay on the ground
            v.command_vertical(dt_s, v.alt_hold_m)
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
            return
        it = self.items[self.current]
        st = self.item_state
        if st == "takeoff":
            v.command_vertical(dt_s, self.takeoff_alt_m)
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
            v.hold_heading()
            if v.airborne and v.alt_m >= self.takeoff_alt_m - v.cfg.takeoff_done_m:
                v.takeoff_in_progress = False
                v.alt_hold_m = self.takeoff_alt_m
                self._reached(v)
        elif st == "go":
            if v.fly_track(dt_s):
                delay_s = max(0.0, it.param1) if math.isfinite(it.param1) else 0.0
                if it.command == mav.MAV_CMD_NAV_LOITER_TIME or delay_s > 0.0:
                    self.item_state = "hold"
                    self.hold_until_ns = v.sim_ns + int(delay_s * 1e9)
                    self.hold_ne = v.track_dest_ne()
                    v.alt_hold_m = self._alt_m(it, v)
                    if it.command == mav.MAV_CMD_NAV_WAYPOINT:
                        v.mission_item_reached(self.current)   # reached on arrival
                else:
                    self.hold_ne = v.track_dest_ne()
                    v.alt_hold_m = self._alt_m(it, v)
                    self._reached(v)
        elif st == "hold":
            v.command_vertical(dt_s, v.alt_hold_m)
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
            if v.sim_ns >= self.hold_until_ns:
                if it.command == mav.MAV_CMD_NAV_LOITER_TIME:
                    self._reached(v)
                else:
                    self._advance(v)
        elif st == "land_approach":
            if v.fly_track(dt_s):
                self.item_state = "land"
        elif st == "land":
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
            v.hold_heading()
            if v.land_descent(dt_s):
                self._reached(v)
                v.disarm_landed("AUTO")
        elif st == "rtl":
            self.rtl.run(v, dt_s)
            if self.rtl.done:
                self._reached(v)

    def _reached(self, v) -> None:
        v.mission_item_reached(self.current)
        self._advance(v)

    def _advance(self, v) -> None:
        self.current += 1
        if self.current >= len(self.items):
            self._complete(v)
        else:
            self._begin(v)

    def _complete(self, v) -> None:
        self.current = len(self.items) - 1
        self.state = mav.MISSION_STATE_COMPLETE
        self.hold_ne = tuple(v.est.pos_ne_m)
        v.alt_hold_m = v.alt_m if v.airborne else 0.0
        v.statustext(mav.MAV_SEVERITY_INFO, "Mission complete")
