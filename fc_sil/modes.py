"""Flight modes with ArduCopter's numbers: what each mode asks of the controllers.

A mode is a small object with ``enter(v)`` (None, or the reason the change is refused, as
ArduCopter's STATUSTEXT words it) and ``run(v, dt_s)`` called at the outer-loop rate. Modes
never touch the C core directly; they use the vehicle's navigation helpers
(fc_sil/vehicle.py ``Vehicle``: ``hold_position``, ``fly_track``, ``pilot_vertical``,
``command_vertical``, ``land_descent``...), so every mode shares one position controller,
one waypoint navigator and one vertical channel, as in ArduCopter.

  STABILIZE 0  pilot lean angles, yaw rate and throttle (MANUAL_CONTROL / RC override)
  ALT_HOLD  2  pilot lean angles and yaw rate; throttle stick = climb rate, centred = hold
  AUTO      3  the mission (mission_exec.py)
  GUIDED    4  GCS targets: take-off, position, velocity (GUID_TIMEOUT), reposition
  LOITER    5  position hold; sticks = acceleration, up to LOIT_SPEED; centred = brake, hold
  RTL       6  climb to RTL_ALT, fly home, loiter RTL_LOIT_TIME, land (or hover RTL_ALT_FINAL)
  LAND      9  hold position (when there is one) and descend; disarm on touchdown; entered by
               a failsafe, it first holds its altitude LAND_WITH_DELAY_S (pause())
  BRAKE    17  stop at 7.5 m/s^2 along a jerk-limited path, then hold
"""

from __future__ import annotations

import math

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .nav_loiter import LoiterNav
from .nav_pos import shifted

# ArduCopter's BRAKE_MODE_DECEL_RATE (750 cm/s^2): Brake stops harder than WPNAV_ACCEL
BRAKE_DECEL_M_S2 = 7.5
# ArduCopter's LAND_WITH_DELAY_MS: a failsafe's LAND (set_mode_land_with_pause) holds its
# altitude this long before descending, so a pilot or the GCS can take over first
LAND_WITH_DELAY_S = 4.0


class Mode:
    number = -1
    name = "?"
    requires_position = False    # needs a horizontal position estimate (GNSS)
    armable = True               # arming allowed in this mode
    manual_throttle = False      # throttle stick sets throttle directly

    def enter(self, v) -> str | None:
        return None

    def exit(self, v) -> None:
        pass

    def run(self, v, dt_s: float) -> None:
        raise NotImplementedError

    def follow_xy_reset(self, v, d_ne) -> None:
        """The estimate jumped by d_ne (vehicle_nav.py): move "hold here" points with it."""

    @property
    def guided_enabled(self) -> bool:
        """HEARTBEAT GUIDED_ENABLED: the horizontal position controller is active."""
        return self.requires_position


class Stabilize(Mode):
    number, name, manual_throttle = CopterMode.STABILIZE, "STABILIZE", True

    def run(self, v, dt_s):
        v.pilot_attitude()
        v.command_throttle(v.pilot_throttle())


class AltHold(Mode):
    number, name = CopterMode.ALT_HOLD, "ALT_HOLD"

    def enter(self, v):
        v.reset_vertical()

    def run(self, v, dt_s):
        v.pilot_attitude()
        v.pilot_vertical(dt_s)


class Loiter(Mode):
    """AC_Loiter: sticks ask for an acceleration, centred sticks brake and hold (nav_loiter)."""
    number, name, requires_position = CopterMode.LOITER, "LOITER", True

    def enter(self, v):
        v.reset_vertical()
        v.reset_horizontal()
        self.nav = LoiterNav(v.cfg.loiter)
        self.nav.reset(v.pos_ctl.vel_desired, v.pos_ctl.accel_desired)

    def run(self, v, dt_s):
        v.pilot_vertical(dt_s)
        roll_in, pitch_in, yaw_in = v.pilot_sticks_rpy()
        v.pilot_yaw(yaw_in)
        self.nav.cfg = v.cfg.loiter          # a PARAM_SET takes effect at once
        # AC_Loiter reads the sticks without a dead zone; ours keep the old 5 % one
        roll_in = roll_in if abs(roll_in) > 0.05 else 0.0
        pitch_in = pitch_in if abs(pitch_in) > 0.05 else 0.0
        v.fly_loiter(dt_s, self.nav, roll_in, pitch_in)


class Brake(Mode):
    """Stop at BRAKE_DECEL_M_S2 along a jerk-limited path (PSC_JERK_XY), then hold there."""
    number, name, requires_position, armable = CopterMode.BRAKE, "BRAKE", True, False

    def enter(self, v):
        v.reset_vertical()
        v.reset_horizontal()
        # ArduCopter: the speed limit is the speed at entry, so the stop never speeds up
        self.speed_m_s = max(math.hypot(*v.est.vel_ne_m_s), 0.5)

    def run(self, v, dt_s):
        v.command_vertical(dt_s, v.alt_hold_m)
        v.hold_position(dt_s, None, (0.0, 0.0), self.speed_m_s,
                        shape_accel_m_s2=BRAKE_DECEL_M_S2)


# GUIDED lives in its own file (every GCS target, as ArduCopter 4.6 takes it); it subclasses
# Mode above, so it is imported here, after Mode exists.
from .mode_guided import Guided  # noqa: E402


class Auto(Mode):
    number, name, requires_position = CopterMode.AUTO, "AUTO", True
    armable = False   # as ArduCopter without AUTO_OPTIONS: arm in GUIDED/LOITER, then AUTO

    def enter(self, v):
        return v.mission.start(v)

    def exit(self, v):
        v.mission.pause(v)

    def run(self, v, dt_s):
        v.mission.run(v, dt_s)

    def follow_xy_reset(self, v, d_ne) -> None:
        v.mission.follow_xy_reset(d_ne)


class Rtl(Mode):
    number, name, requires_position, armable = CopterMode.RTL, "RTL", True, False

    def enter(self, v):
        if not v.home_set:
            return "RTL: no home position"
        if not v.airborne:
            return "RTL: vehicle is landed"
        v.reset_vertical()
        self.seq = RtlSequence(v)
        return None

    def run(self, v, dt_s):
        self.seq.run(v, dt_s)

    @property
    def phase(self) -> str:
        return self.seq.phase


class RtlSequence:
    """climb -> return -> loiter -> land (or hover at RTL_ALT_FINAL); also AUTO's RTL item."""

    def __init__(self, v):
        cfg = v.cfg
        # home, or the nearest rally point (fc_sil/rally.py)
        target = v.rally.rtl_destination(v)
        self.dest_ne = target.ne
        self.rally_index = target.rally_index
        # RTL_ALT, RTL_ALT_FINAL and the fence's altitudes are above home
        self.return_alt_m = max(v.alt_m + cfg.rtl_climb_min_m, v.alt_from_home(cfg.rtl_alt_m))
        if target.alt_m is not None:
            self.return_alt_m = max(self.return_alt_m, target.alt_m)
        safe_max = v.fence.safe_alt_max(v)
        if safe_max is not None:      # ArduCopter: RTL stays below an enabled max-alt fence
            self.return_alt_m = min(self.return_alt_m, v.alt_from_home(safe_max))
        home_dist = math.hypot(v.est.pos_ne_m[0] - self.dest_ne[0],
                               v.est.pos_ne_m[1] - self.dest_ne[1])
        if home_dist < cfg.wp.radius_m:
            # already over home: ArduCopter does not climb then
            self.return_alt_m = max(v.alt_m, v.alt_from_home(max(cfg.rtl_alt_final_m, 0.0)))
        self.phase = "climb"
        self.loiter_until_ns = None
        self.done = False
        v.start_track(v.est.pos_ne_m, self.return_alt_m, None)

    def run(self, v, dt_s):
        cfg = v.cfg
        if self.phase == "climb":
            if v.fly_track(dt_s):
                speed = cfg.rtl_speed_m_s or None
                v.start_track(self.dest_ne, self.return_alt_m, speed)
                self.phase = "return"
                v.face_track(rtl=True)
        elif self.phase == "return":
            if v.fly_track(dt_s):
                self.phase = "loiter"
                self.loiter_until_ns = v.sim_ns + int(cfg.rtl_loit_time_s * 1e9)
        elif self.phase == "loiter":
            v.command_vertical(dt_s, self.return_alt_m)
            v.hold_position(dt_s, self.dest_ne, (0.0, 0.0), cfg.wp.speed_m_s)
            if v.sim_ns >= self.loiter_until_ns:
                if cfg.rtl_alt_final_m > 0.0:
                    v.start_track(self.dest_ne, v.alt_from_home(cfg.rtl_alt_final_m), None)
                    self.phase = "final"
                else:
                    self.phase = "land"
        elif self.phase == "final":
            if v.fly_track(dt_s):
                self.phase = "hover"
        elif self.phase == "hover":
            v.command_vertical(dt_s, v.alt_from_home(cfg.rtl_alt_final_m))
            v.hold_position(dt_s, self.dest_ne, (0.0, 0.0), cfg.wp.speed_m_s)
            self.done = True
        elif self.phase == "land":
            v.hold_position(dt_s, self.dest_ne, (0.0, 0.0), cfg.wp.speed_m_s)
            if v.land_descent(dt_s):
                self.phase = "landed"
                self.done = True
                v.disarm_landed("RTL")


class Land(Mode):
    number, name, armable = CopterMode.LAND, "LAND", False

    def enter(self, v):
        v.reset_horizontal()
        self.hold_ne = tuple(v.est.pos_ne_m) if v.position_ok() else None
        self.pause_until_ns = -1
        if v.armed and not v.airborne:
            v.disarm_landed("LAND")

    def follow_xy_reset(self, v, d_ne) -> None:
        if self.hold_ne is not None:
            self.hold_ne = shifted(self.hold_ne, d_ne)

    def pause(self, v) -> None:
        """A failsafe's LAND: hold the altitude LAND_WITH_DELAY_S first, as ArduCopter."""
        self.pause_until_ns = v.sim_ns + int(LAND_WITH_DELAY_S * 1e9)

    @property
    def guided_enabled(self) -> bool:
        return self.hold_ne is not None

    def run(self, v, dt_s):
        if self.hold_ne is not None and v.position_ok():
            v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), v.cfg.wp.speed_m_s)
        else:
            self.hold_ne = None
            v.command_attitude(0.0, 0.0)     # no position: land level, drift with the wind
        v.hold_heading()
        if v.airborne and v.sim_ns < self.pause_until_ns:
            v.command_climb(dt_s, 0.0)
        elif v.land_descent(dt_s):
            v.disarm_landed("LAND")


MODES: dict[int, type[Mode]] = {m.number: m for m in
                                (Stabilize, AltHold, Auto, Guided, Loiter, Rtl, Land, Brake)}
MODE_NAMES = {n: m.name for n, m in MODES.items()}
