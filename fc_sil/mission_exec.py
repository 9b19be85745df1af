"""Mission execution for AUTO: the MissionStore's items (home at seq 0), as ArduCopter runs them.

Which command runs when is mission_seq.py's MissionCursor (AP_Mission's rules, DO_JUMP
included): one navigation command at a time (mission_nav.py, mission_land.py), and beside
it, one at a time, the DO / CONDITION commands found before it:

  DO_CHANGE_SPEED     p1 0/1 (air/ground speed), p2 m/s > 0: the horizontal speed
  DO_SET_ROI(_LOCATION) face the item's location (0, 0, 0: stop), DO_SET_ROI_NONE: stop
  CONDITION_DELAY     hold back the DO commands after it for p1 seconds
  CONDITION_YAW       turn to p1 deg at p2 deg/s (0: ATC_SLEW_YAW), p3 direction, p4 relative

Altitudes: relative frames above home, absolute frames above mean sea level, terrain frames
as relative (no terrain data). A position of lat/lon 0 means where the previous leg ended
(or here), an altitude of 0 the altitude there, as ArduCopter's loc_from_cmd.

What a GCS sees, as ArduCopter 4.6 sends it: "Mission: <seq> <type>" when a command starts
(and "Mission: <seq> Jump <n>/<total>" when a DO_JUMP is taken); MISSION_ITEM_REACHED when one
completes, DO commands included (ArduCopter sends the item-reached message deferred, so of
several completing in the same step only the last goes out: WP 2 then its DO 3 gives one
MISSION_ITEM_REACHED 3; the vehicle's "Reached command #<seq>" text goes with it, which
ArduCopter sends for waypoints and loiters only);
MISSION_CURRENT reports the navigation command (after a DO_JUMP its target), ACTIVE, PAUSED
(AUTO left), COMPLETE after the last command. Starting AUTO armed on the ground needs a
TAKEOFF first ("Auto: Missing Takeoff Cmd"). After the last command the vehicle holds
position where it is (or stays landed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .mission_land import LandRun, RtlRun, TakeoffRun
from .mission_nav import CircleRun, DelayRun, SplineRun, WaypointRun
from .mission_seq import MissionCursor
from .mission_yaw import MissionYaw
from .nav_pos import shifted
from .nav_spline import SplineLimits

REL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                        mav.MAV_FRAME_GLOBAL_TERRAIN_ALT, mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})
RUNNERS = {mav.MAV_CMD_NAV_TAKEOFF: TakeoffRun, mav.MAV_CMD_NAV_WAYPOINT: WaypointRun,
           mav.MAV_CMD_NAV_LOITER_TIME: WaypointRun, mav.MAV_CMD_NAV_SPLINE_WAYPOINT: SplineRun,
           mav.MAV_CMD_NAV_LOITER_TURNS: CircleRun, mav.MAV_CMD_NAV_DELAY: DelayRun,
           mav.MAV_CMD_NAV_LAND: LandRun, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH: RtlRun}
NAV_COMMANDS = frozenset(RUNNERS)
# AP_Mission's names in "Mission: <seq> <name>"
TYPE_NAMES = {mav.MAV_CMD_NAV_TAKEOFF: "Takeoff", mav.MAV_CMD_NAV_WAYPOINT: "WP",
              mav.MAV_CMD_NAV_LOITER_TIME: "LoitTime", mav.MAV_CMD_NAV_SPLINE_WAYPOINT: "SplineWP",
              mav.MAV_CMD_NAV_LOITER_TURNS: "LoitTurns", mav.MAV_CMD_NAV_DELAY: "Delay",
              mav.MAV_CMD_NAV_LAND: "Land", mav.MAV_CMD_NAV_RETURN_TO_LAUNCH: "RTL",
              mav.MAV_CMD_DO_CHANGE_SPEED: "ChangeSpeed", mav.MAV_CMD_DO_SET_ROI: "SetROI",
              mav.MAV_CMD_DO_SET_ROI_LOCATION: "SetROILocation",
              mav.MAV_CMD_DO_SET_ROI_NONE: "SetROINone", mav.MAV_CMD_CONDITION_DELAY: "CondDelay",
              mav.MAV_CMD_CONDITION_YAW: "CondYaw"}


@dataclass
class MissionConfig:
    circle_radius_m: float = 10.0          # CIRCLE_RADIUS / 100
    circle_rate_rad_s: float = math.radians(20.0)   # CIRCLE_RATE
    accel_z_m_s2: float = 1.0              # WPNAV_ACCEL_Z / 100
    jerk_m_s3: float = 1.0                 # WPNAV_JERK

    @classmethod
    def from_store(cls, get) -> "MissionConfig":
        return cls(circle_radius_m=get("CIRCLE_RADIUS") * 0.01,
                   circle_rate_rad_s=math.radians(get("CIRCLE_RATE")),
                   accel_z_m_s2=get("WPNAV_ACCEL_Z") * 0.01, jerk_m_s3=get("WPNAV_JERK"))


class MissionExecutor:
    def __init__(self):
        self.items: tuple = ()
        self.cursor = MissionCursor()
        self.current = 0                 # the navigation command's seq (0: not started)
        self.state = mav.MISSION_STATE_NOT_STARTED
        self.nav = None                  # the navigation command's runner
        self.do_started_ns = None
        self.yaw = MissionYaw()
        self.leg_end = None              # mission_nav.LegEnd of the last waypoint-type leg
        self.hold_ne = None
        self.cfg = MissionConfig()
        self._reached = None             # the last command completed in this step
        self._v = None

    # ---- from the GCS -----------------------------------------------------------------

    def set_items(self, items, v) -> None:
        """A new mission; a running one restarts at item 1 the next time AUTO starts."""
        self.items = tuple(items)
        self.cursor = MissionCursor(self.items)
        self.current = 0
        self.nav = None
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
        if self.state == mav.MISSION_STATE_COMPLETE:
            # AP_Mission: the next start resumes here, every jump unused again
            self.cursor.reset()
            self.state = mav.MISSION_STATE_PAUSED
        if v.mode.number == CopterMode.AUTO and self.state == mav.MISSION_STATE_ACTIVE:
            self._load(v, seq)
        return None

    def count(self) -> int:
        return max(0, len(self.items) - 1)

    @property
    def item_state(self) -> str | None:
        return self.nav.state if self.nav is not None else None

    # ---- mode hooks -------------------------------------------------------------------

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
            self.cursor.reset()
        if v.armed and not v.airborne and not self.cursor.starts_with_takeoff(self.current):
            return "Auto: Missing Takeoff Cmd"
        self.cfg = MissionConfig.from_store(v.store.host)
        self.yaw.begin(v)
        self.state = mav.MISSION_STATE_ACTIVE
        self._load(v, self.current)
        return None

    def on_disarm(self) -> None:
        """ArduCopter resets the mission at every disarm: MISSION_CURRENT reports 0 and the
        next AUTO starts from the first item, every jump unused."""
        self.current = 0
        self.cursor.reset()
        self.nav = None

    def pause(self, v) -> None:
        if self.state == mav.MISSION_STATE_ACTIVE:
            self.state = mav.MISSION_STATE_PAUSED
        v.takeoff_in_progress = False

    # ---- what runners share -----------------------------------------------------------

    def alt_m(self, it, v) -> float:
        if it.frame in REL_FRAMES:
            return v.alt_from_home(float(it.z))
        return v.alt_from_msl(float(it.z))

    def loc(self, it, v, default=None):
        """(n, e, up) of an item; lat/lon 0 and altitude 0 take the default's (the end of
        the last leg, else where the vehicle is)."""
        if default is None:
            default = self.leg_end.point if self.leg_end is not None else \
                (v.est.pos_ne_m[0], v.est.pos_ne_m[1], v.alt_m)
        ne = default[:2] if it.x == 0 and it.y == 0 else v.est.origin.to_ne(it.x, it.y)
        alt = default[2] if it.z == 0 else self.alt_m(it, v)
        return (float(ne[0]), float(ne[1]), float(alt))

    def next_nav(self, index: int):
        j = self.cursor.next_nav(index + 1)
        return None if j is None else self.items[j]

    def spline_limits(self, v) -> SplineLimits:
        wp = v.cfg.wp
        return SplineLimits(speed_xy_m_s=v.speed_override_m_s or wp.speed_m_s,
                            speed_up_m_s=wp.up_m_s, speed_dn_m_s=wp.dn_m_s,
                            accel_xy_m_s2=wp.accel_m_s2, accel_z_m_s2=self.cfg.accel_z_m_s2,
                            jerk_m_s3=self.cfg.jerk_m_s3, radius_m=wp.radius_m,
                            pos_p=v.cfg.pos.pos_p)

    def say(self, text: str) -> None:
        if self._v is not None:
            self._v.statustext(mav.MAV_SEVERITY_INFO, text)

    # ---- execution --------------------------------------------------------------------

    def _load(self, v, start: int) -> None:
        """Make the navigation command at or after `start` current (ArduCopter's
        set_current_cmd / the advance after a command completes)."""
        self._v = v
        nav, first_do = self.cursor.advance_nav(start)
        self._flush_texts(v)
        if first_do is not None:
            self._start_do(v, first_do)
        if nav is None:
            self._complete(v)
            return
        self.current = nav
        it = self.items[nav]
        v.statustext(mav.MAV_SEVERITY_INFO, f"Mission: {nav} {TYPE_NAMES[it.command]}")
        self.nav = RUNNERS[it.command](self, v, nav, it)

    def follow_xy_reset(self, d_ne) -> None:
        """The estimate jumped (vehicle_nav.py): the hold after the mission and the running
        command's "hold here" point move with it."""
        if self.hold_ne is not None:
            self.hold_ne = shifted(self.hold_ne, d_ne)
        if self.nav is not None:
            self.nav.follow_xy_reset(d_ne)

    def run(self, v, dt_s: float) -> None:
        self._v = v
        self._reached = None
        if self.state != mav.MISSION_STATE_ACTIVE or self.nav is None:
            # complete (or no mission): hold where we are, or stay on the ground
            v.command_vertical(dt_s, v.alt_hold_m)
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
            self.yaw.apply(v, dt_s, (0.0, 0.0), v.cfg.wp.speed_m_s)
            return
        nav, seq = self.nav, self.current
        if nav.run(self, v, dt_s):
            self._reached = seq
            if not v.armed:              # landed and disarmed: the mission ends here
                self._complete(v)
            elif self.state == mav.MISSION_STATE_ACTIVE:
                self._load(v, seq + 1)
        self._run_do(v)
        if not nav.own_yaw:
            speed = v.speed_override_m_s or v.cfg.wp.speed_m_s
            self.yaw.apply(v, dt_s, v.pos_ctl.vel_desired, speed, nav.circle_yaw_rad)
        if self._reached is not None:
            v.mission_item_reached(self._reached)

    def _run_do(self, v) -> None:
        c = self.cursor
        if self.state != mav.MISSION_STATE_ACTIVE:
            return
        if not c.do_loaded:
            j = c.advance_do()
            if j is not None:
                self._start_do(v, j)
        elif self._verify_do(v, self.items[c.do_index]):
            c.do_loaded = False
            self._reached = c.do_index

    def _start_do(self, v, j: int) -> None:
        it = self.items[j]
        c = it.command
        v.statustext(mav.MAV_SEVERITY_INFO, f"Mission: {j} {TYPE_NAMES.get(c, '?')}")
        self.do_started_ns = v.sim_ns
        if c == mav.MAV_CMD_DO_CHANGE_SPEED:
            if it.param2 > 0 and int(it.param1) in (0, 1):
                v.change_speed(float(it.param2), int(it.param1))
        elif c in (mav.MAV_CMD_DO_SET_ROI, mav.MAV_CMD_DO_SET_ROI_LOCATION,
                   mav.MAV_CMD_DO_SET_ROI_NONE):
            at_zero = it.x == 0 and it.y == 0 and it.z == 0
            none = c == mav.MAV_CMD_DO_SET_ROI_NONE or at_zero
            self.yaw.set_roi(v, None if none else v.est.origin.to_ne(it.x, it.y))
        elif c == mav.MAV_CMD_CONDITION_YAW:
            self.yaw.set_fixed(v, it.param1, it.param2, int(it.param3), it.param4 > 0)

    def _verify_do(self, v, it) -> bool:
        if it.command == mav.MAV_CMD_CONDITION_DELAY:
            return v.sim_ns - self.do_started_ns > max(0.0, it.param1) * 1e9
        if it.command == mav.MAV_CMD_CONDITION_YAW:
            self.yaw.keep_fixed(v)       # a waypoint may have taken the heading back
            return self.yaw.fixed_reached(v)
        return True

    def _flush_texts(self, v) -> None:
        for text in self.cursor.texts:
            v.statustext(mav.MAV_SEVERITY_INFO, text)
        self.cursor.texts.clear()

    def _complete(self, v) -> None:
        self.state = mav.MISSION_STATE_COMPLETE
        self.nav = None
        self.hold_ne = tuple(v.est.pos_ne_m)
        self.yaw.hold(v)
        v.alt_hold_m = v.alt_m if v.airborne else 0.0
        v.statustext(mav.MAV_SEVERITY_INFO, "Mission complete")
