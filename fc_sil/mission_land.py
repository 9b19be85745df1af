"""Take-off, LAND and RTL as mission commands (the runners of mission_nav.py's kind).

  NAV_TAKEOFF  climb where the vehicle stands to z (at least the minimum take-off height);
               already that high in the air: complete at once. Heading held.
  NAV_LAND     lat/lon given: fly there at the present height, then descend; else descend
               here. Heading held. Complete at touchdown (the vehicle disarms).
  RTL          the RTL mode's sequence (modes.RtlSequence); complete once landed (or
               hovering at RTL_ALT_FINAL).
"""

from __future__ import annotations

from .mission_nav import Runner
from .modes import RtlSequence
from .nav_pos import shifted


class TakeoffRun(Runner):
    state = "takeoff"

    def __init__(self, ex, v, index: int, it):
        self.alt_m = max(ex.alt_m(it, v), v.cfg.takeoff_min_m)
        self.hold_ne = tuple(v.est.pos_ne_m)
        ex.yaw.hold(v)
        ex.leg_end = None
        self.already = v.airborne and v.alt_m >= self.alt_m - v.cfg.takeoff_done_m
        if not self.already:
            v.takeoff_in_progress = True

    def follow_xy_reset(self, d_ne) -> None:
        self.hold_ne = shifted(self.hold_ne, d_ne)

    def run(self, ex, v, dt_s):
        if self.already:             # ArduCopter skips the climb when already up there
            return True
        v.command_vertical(dt_s, self.alt_m)
        v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
        v.hold_heading()
        if v.airborne and v.alt_m >= self.alt_m - v.cfg.takeoff_done_m:
            v.takeoff_in_progress = False
            v.alt_hold_m = self.alt_m
            return True
        return False


class LandRun(Runner):
    def __init__(self, ex, v, index: int, it):
        ex.yaw.hold(v)
        ex.leg_end = None
        self.here = it.x == 0 and it.y == 0     # land where we are, not at a place
        if self.here:
            self.ne = tuple(v.est.pos_ne_m)
            self.state = "land"
        else:
            self.ne = v.est.origin.to_ne(it.x, it.y)
            v.start_track(self.ne, v.alt_m, v.speed_override_m_s)
            self.state = "land_approach"

    def follow_xy_reset(self, d_ne) -> None:
        if self.here:
            self.ne = shifted(self.ne, d_ne)

    def run(self, ex, v, dt_s):
        if self.state == "land_approach":
            if v.fly_track(dt_s):
                self.state = "land"
            return False
        v.hold_position(dt_s, self.ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
        v.hold_heading()
        if v.land_descent(dt_s):
            v.disarm_landed("AUTO")
            return True
        return False


class RtlRun(Runner):
    state = "rtl"
    own_yaw = True

    def __init__(self, ex, v, index: int, it):
        ex.leg_end = None
        ex.yaw.hold(v)
        self.seq = RtlSequence(v)

    def run(self, ex, v, dt_s):
        self.seq.run(v, dt_s)
        return self.seq.done
