"""The navigation commands of a mission: one runner per kind, as ArduCopter's AUTO flies them.

A runner is built when its command starts (``start``) and stepped every outer-loop step
(``run``, which returns True when the command is complete: ArduCopter's verify). The
mission executor (mission_exec.py) passes itself as ``ex`` for what runners share: the
item's location (``ex.loc``), the auto-yaw (mission_yaw.py), where the previous leg ended
(``ex.leg_end``, for spline tangents) and the look-ahead to the next navigation command.

  NAV_WAYPOINT     straight leg (the vehicle's waypoint navigator), then p1 seconds' hold
  LOITER_TIME      the same; p1 is the hold time
  SPLINE_WAYPOINT  a spline leg (nav_spline.py), then p1 seconds' hold
  LOITER_TURNS     fly to the circle's edge when more than 3 m away, then p1 turns of radius
                   |p3| m (0: CIRCLE_RADIUS), counter-clockwise when p3 < 0 (nav_circle.py)
  NAV_DELAY        hold where the last command left the vehicle for p1 seconds
Take-off, LAND and RTL runners live in mission_land.py.

Delays are whole seconds, as ArduCopter stores them (p1 truncated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

from .nav_circle import CircleNav
from .nav_spline import SplineLeg, SplineNav
from silbridge.shm.records import NS_PER_S as _NS

CIRCLE_EDGE_MIN_M = 3.0           # ArduCopter flies to the circle's edge when farther
CIRCLE_FACE_EDGE_MIN_M = 5.0      # and faces it on the way when this far from the centre


@dataclass
class LegEnd:
    """Where the last waypoint-type leg ended, for the next spline's origin and tangent."""
    point: tuple                      # (n, e, up)
    exit_vec: tuple = (0.0, 0.0, 0.0)  # the leg's direction there (per unit spline time)
    fast: bool = False                # the leg flew on into the next one without stopping
    exit_speed_m_s: float = 0.0


def _hold(v, dt_s: float, ne, alt_m: float) -> None:
    v.command_vertical(dt_s, alt_m)
    v.hold_position(dt_s, ne, (0.0, 0.0), v.cfg.wp.speed_m_s)


class Runner:
    state = "go"
    circle_yaw_rad = None             # the heading that faces a circle's centre, if circling
    own_yaw = False                   # the runner steers the heading itself (RTL)

    def run(self, ex, v, dt_s: float) -> bool:
        raise NotImplementedError

    def follow_xy_reset(self, d_ne) -> None:
        """The estimate jumped by d_ne: move a "hold here" point (vehicle_nav.py)."""


class HoldTimer:
    """A command's hold after arrival (p1 whole seconds)."""

    def __init__(self, seconds: float):
        self.seconds = int(seconds) if math.isfinite(seconds) and seconds > 0 else 0
        self.since_ns = None

    def done(self, v) -> bool:
        if self.since_ns is None:
            self.since_ns = v.sim_ns
        return v.sim_ns - self.since_ns >= self.seconds * _NS


class WaypointRun(Runner):
    def __init__(self, ex, v, index: int, it):
        self.dest = ex.loc(it, v)
        self.start = (v.est.pos_ne_m[0], v.est.pos_ne_m[1], v.alt_target_m)
        v.start_track(self.dest[:2], self.dest[2], v.speed_override_m_s)
        ex.yaw.nav_default(v)
        self.timer = HoldTimer(it.param1)
        nxt = ex.next_nav(index)
        self.fast_into_spline = (self.timer.seconds == 0 and nxt is not None
                                 and nxt.command == mav.MAV_CMD_NAV_SPLINE_WAYPOINT)

    def run(self, ex, v, dt_s):
        if self.state == "go":
            if not v.fly_track(dt_s):
                return False
            self.state = "hold"
            vec = tuple(b - a for a, b in zip(self.start, self.dest))
            ex.leg_end = LegEnd(self.dest, vec, self.fast_into_spline)
        _hold(v, dt_s, self.dest[:2], self.dest[2])
        return self.timer.done(v)


class SplineRun(Runner):
    def __init__(self, ex, v, index: int, it):
        self.nav = SplineNav(ex.spline_limits(v))
        self.dest = ex.loc(it, v)
        end = ex.leg_end
        origin = end.point if end is not None else (v.est.pos_ne_m[0], v.est.pos_ne_m[1],
                                                    v.alt_m)
        origin_vec = end.exit_vec if end is not None and end.fast else (0.0, 0.0, 0.0)
        self.timer = HoldTimer(it.param1)
        dest_vec, nxt = self._exit(ex, v, index, origin)
        start_speed = end.exit_speed_m_s if end is not None and end.fast else 0.0
        self.nav.set_leg(origin, self.dest, origin_vec, dest_vec, start_speed)
        if nxt is not None:
            # the next spline leg cannot start faster than its own limits allow
            j, nxt_it = nxt
            nxt_dest = ex.loc(nxt_it, v, self.dest)
            nxt_vec, _ = self._exit(ex, v, j, self.dest, nxt_it, nxt_dest)
            leg = SplineLeg(self.dest, nxt_dest, dest_vec, nxt_vec, self.nav.lim)
            self.nav.set_destination_speed_max(leg.origin_speed_max)
        ex.yaw.nav_default(v)

    def _exit(self, ex, v, index, origin, it=None, dest=None):
        """(this leg's end vector, (index, item) of a following spline or None)."""
        it = it if it is not None else ex.items[index]
        dest = dest if dest is not None else self.dest
        if int(it.param1) > 0:
            return (0.0, 0.0, 0.0), None          # a hold here: the leg ends at rest
        j = ex.cursor.next_nav(index + 1)
        if j is None:
            return (0.0, 0.0, 0.0), None
        nxt = ex.items[j]
        nxt_dest = ex.loc(nxt, v, dest)
        if nxt.command == mav.MAV_CMD_NAV_SPLINE_WAYPOINT:
            return tuple(b - a for a, b in zip(origin, nxt_dest)), (j, nxt)
        return tuple(b - a for a, b in zip(dest, nxt_dest)), None

    def run(self, ex, v, dt_s):
        if self.state == "go":
            vel = (v.est.vel_ne_m_s[0], v.est.vel_ne_m_s[1], v.climb_m_s)
            tp, tv, talt = self.nav.update(dt_s, v.est.pos_ne_m, v.alt_m, vel)
            v.hold_position(dt_s, tp, tv, self.nav.lim.speed_xy_m_s)
            v.command_vertical(dt_s, talt)
            v.alt_hold_m = self.dest[2]
            if not self.nav.reached(v.est.pos_ne_m, v.alt_m):
                return False
            self.state = "hold"
            ex.leg_end = LegEnd(self.dest, self.nav.leg.dest_vec, self.nav.ends_moving,
                                self.nav.speed_m_s)
            if self.nav.ends_moving:
                return self.timer.done(v)
        _hold(v, dt_s, self.dest[:2], self.dest[2])
        return self.timer.done(v)


class CircleRun(Runner):
    def __init__(self, ex, v, index: int, it):
        here = (v.est.pos_ne_m[0], v.est.pos_ne_m[1], v.alt_m)
        center = ex.loc(it, v, here)
        r = abs(it.param3)
        radius = int(min(255.0, r)) if r <= 255.0 else int(min(255.0, r * 0.1)) * 10
        if radius == 0:
            radius = ex.cfg.circle_radius_m
        rate = abs(ex.cfg.circle_rate_rad_s) * (-1.0 if it.param3 < 0 else 1.0)
        self.turns = int(min(255.0, max(0.0, it.param1)))
        speed = v.speed_override_m_s or v.cfg.wp.speed_m_s
        self.circle = CircleNav(center[:2], radius, rate, speed, v.cfg.wp.accel_m_s2)
        self.alt_m = center[2]
        ex.leg_end = None
        edge = self.circle.closest_edge(v.est.pos_ne_m, v.yaw_rad)
        if math.dist(edge, v.est.pos_ne_m) > CIRCLE_EDGE_MIN_M:
            v.start_track(edge, self.alt_m, v.speed_override_m_s)
            self.state = "to_edge"
            to_center = math.dist(center[:2], v.est.pos_ne_m)
            if not ex.yaw.roi_active:
                if to_center > radius and to_center > CIRCLE_FACE_EDGE_MIN_M:
                    ex.yaw.nav_default(v)
                else:
                    ex.yaw.hold(v)      # inside the circle: do not spin on the way out
        else:
            self.alt_m = v.alt_m        # circles at the height it is at
            self._begin(ex, v)

    def _begin(self, ex, v) -> None:
        self.circle.start(v.est.pos_ne_m, v.yaw_rad)
        self.state = "circle"
        v.alt_hold_m = self.alt_m
        ex.yaw.circle(v)

    def run(self, ex, v, dt_s):
        if self.state == "to_edge":
            if v.fly_track(dt_s):
                self._begin(ex, v)
            return False
        tp, tv, ta = self.circle.update(dt_s)
        v.hold_position(dt_s, tp, tv, v.cfg.wp.speed_m_s, ta)
        v.command_vertical(dt_s, self.alt_m)
        self.circle_yaw_rad = self.circle.yaw_rad(tp)
        return self.circle.turns_done >= self.turns


class DelayRun(Runner):
    """NAV_DELAY: the vehicle keeps doing what the last command left it doing (holding)."""
    state = "hold"

    def __init__(self, ex, v, index: int, it):
        self.seconds = float(it.param1) if math.isfinite(it.param1) and it.param1 > 0 else 0.0
        if self.seconds <= 0.0:
            ex.say("NAV_DELAY: absolute times need a clock, no delay")
        ex.say(f"Delaying {int(self.seconds)} sec")
        self.until_ns = v.sim_ns + int(self.seconds * _NS)
        end = ex.leg_end
        self.ne = tuple(end.point[:2]) if end else tuple(v.est.pos_ne_m)
        self.alt_m = end.point[2] if end else v.alt_hold_m

    def run(self, ex, v, dt_s):
        _hold(v, dt_s, self.ne, self.alt_m)
        return v.sim_ns > self.until_ns
