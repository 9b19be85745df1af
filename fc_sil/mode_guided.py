"""GUIDED: every target a GCS or companion computer gives, flown as ArduCopter 4.6's ModeGuided.

One sub-mode at a time, chosen by the last target (ArduCopter/mode_guided.cpp):

  TAKEOFF      NAV_TAKEOFF: climb where we are, heading held
  POS          a position (SET_POSITION_TARGET position only, DO_REPOSITION): the target is
               approached along a jerk-limited path (WPNAV_SPEED, WPNAV_ACCEL, PSC_JERK_XY);
               GUID_OPTIONS bit 6 flies it with the waypoint navigator instead (WP)
  VELACCEL     a velocity (+ acceleration): the mode's state on entry (velocity 0 = stop and
               hold) and after any refused target
  ACCEL        an acceleration alone
  POSVELACCEL  position + velocity (+ acceleration): the target moves on with its velocity
  ANGLE        SET_ATTITUDE_TARGET: lean angles or body rates, thrust as a climb rate
               (GUID_OPTIONS bit 3: as thrust)

GUID_TIMEOUT after the last velocity, acceleration or attitude target the vehicle stops
(velocity and acceleration 0; ANGLE levels out, climb 0) and a commanded yaw rate ends.
Position targets do not time out. While landed only TAKEOFF (and ANGLE with a positive
climb or thrust) leaves the ground, as in ArduCopter. Yaw: auto_yaw.py (AutoYaw chooses the
heading, HeadingControl gets it to the core).

Import fc_sil.modes, not this module, first: this class subclasses modes.Mode and modes.py
imports it back to list it in MODES.
"""

from __future__ import annotations

import math
from enum import Enum

from silbridge.mavlink.gcs.vehicle_api import CopterMode

from .auto_yaw import (NO_YAW, AutoYaw, HeadingControl, YawConfig, YawMode, YawRequest,
                       wrap_pi)
from .modes import Mode
from .nav_kinematics import advance_xy, shape_pos_vel_accel_xy
from .nav_pos import shifted
from silbridge.shm.records import NS_PER_S as _NS

# GUID_OPTIONS bits (ArduCopter ModeGuided::Option)
OPT_IGNORE_PILOT_YAW = 1 << 2
OPT_THRUST_AS_THRUST = 1 << 3
OPT_WPNAV_FOR_POS = 1 << 6
PILOT_YAW_DEADZONE = 0.05      # the same stick dead zone as the vehicle's other modes


class Sub(Enum):
    TAKEOFF = "takeoff"
    WP = "wp"
    POS = "pos"
    VELACCEL = "velaccel"
    ACCEL = "accel"
    POSVELACCEL = "posvelaccel"
    ANGLE = "angle"


class Guided(Mode):
    number, name, requires_position = CopterMode.GUIDED, "GUIDED", True

    # ---- entry and configuration ---------------------------------------------------------
    def enter(self, v):
        v.reset_vertical()
        v.reset_horizontal()
        self._cfg_version = None
        self._refresh(v)
        self.auto_yaw = AutoYaw(v.yaw_rad)
        self.heading = HeadingControl(v.yaw_rad)
        self.takeoff_alt_m = None
        self.takeoff_done = False
        self.hold_ne = tuple(v.est.pos_ne_m)
        self.init(v)

    @property
    def thrust_as_thrust(self) -> bool:
        """GUID_OPTIONS bit 3: SET_ATTITUDE_TARGET's thrust is thrust, not a climb rate."""
        return bool(self.options & OPT_THRUST_AS_THRUST)

    def _refresh(self, v) -> None:
        if self._cfg_version == v.store.version:
            return
        self._cfg_version = v.store.version
        get = v.store.host
        self.ycfg = YawConfig.from_store(get)
        self.options = int(get("GUID_OPTIONS"))
        self.timeout_ns = int(max(v.cfg.guid_timeout_s, 0.1) * _NS)

    def init(self, v) -> None:
        """ArduCopter's init(true): stop (velocity and acceleration 0) and hold. Also what a
        refused target does."""
        self._velaccel_start(v)
        self.vel_ned = (0.0, 0.0, 0.0)
        self.acc_ned = (0.0, 0.0, 0.0)
        self.update_ns = v.sim_ns

    def _pva_start(self, v, sub: Sub) -> None:
        """A new position/velocity/acceleration sub-mode: speeds back to WPNAV_*, controllers
        taken over from the present state, yaw to WP_YAW_BEHAVIOR's default."""
        self._end_takeoff(v)
        self.sub = sub
        self.speed_m_s = v.cfg.wp.speed_m_s
        self.up_m_s, self.dn_m_s = v.cfg.wp.up_m_s, v.cfg.wp.dn_m_s
        v.reset_horizontal()
        if v.airborne:
            v.reset_vertical()
        self.pos_d = tuple(v.est.pos_ne_m)
        self.vel_d = tuple(v.est.vel_ne_m_s)
        self.acc_d = (0.0, 0.0)
        self.alt_goal_m = v.alt_m
        self.auto_yaw.set_default(self.ycfg.wp_yaw_behavior, v.yaw_rad)

    def _velaccel_start(self, v) -> None:
        self._pva_start(v, Sub.VELACCEL)

    def _end_takeoff(self, v) -> None:
        """Any other target ends a take-off where it got to (ArduCopter holds the height
        reached, not the pre-take-off 0 m)."""
        if getattr(self, "sub", None) == Sub.TAKEOFF and not self.takeoff_done:
            v.takeoff_in_progress = False
            v.alt_hold_m = v.alt_m

    def follow_xy_reset(self, v, d_ne) -> None:
        """The estimate jumped (vehicle_nav.py): the take-off's hold point and the shaped path
        toward a destination move with it, as ArduCopter's position controller targets do;
        the destination itself is a place and stays."""
        self.hold_ne = shifted(self.hold_ne, d_ne)
        self.pos_d = shifted(self.pos_d, d_ne)

    # ---- targets (called by vehicle_commands.py) -------------------------------------------
    def start_takeoff(self, v, alt_m: float) -> None:
        self.sub = Sub.TAKEOFF
        self.takeoff_alt_m = alt_m
        self.takeoff_done = False
        self.hold_ne = tuple(v.est.pos_ne_m)
        self.auto_yaw.set_mode(YawMode.HOLD, v.yaw_rad)
        v.takeoff_in_progress = True

    def set_destination(self, v, ne, alt_m: float, yaw: YawRequest = NO_YAW) -> None:
        wp = bool(self.options & OPT_WPNAV_FOR_POS)
        want = Sub.WP if wp else Sub.POS
        if self.sub != want:
            self._pva_start(v, want)
        self._set_yaw(v, yaw)
        self.dest_ne = (float(ne[0]), float(ne[1]))
        self.alt_goal_m = float(alt_m)
        self.vel_ned = self.acc_ned = (0.0, 0.0, 0.0)
        self.update_ns = v.sim_ns
        if wp:
            v.start_track(self.dest_ne, self.alt_goal_m, self.speed_m_s)

    def set_posvelaccel(self, v, ne, alt_m: float, vel_ned, acc_ned, yaw: YawRequest) -> None:
        if self.sub != Sub.POSVELACCEL:
            self._pva_start(v, Sub.POSVELACCEL)
        self._set_yaw(v, yaw)
        self.dest_ne = (float(ne[0]), float(ne[1]))
        self.alt_goal_m = float(alt_m)
        self.vel_ned, self.acc_ned = tuple(vel_ned), tuple(acc_ned)
        self.update_ns = v.sim_ns

    def set_velaccel(self, v, vel_ned, acc_ned, yaw: YawRequest) -> None:
        if self.sub != Sub.VELACCEL:
            self._velaccel_start(v)
        self._set_yaw(v, yaw)
        self.vel_ned, self.acc_ned = tuple(vel_ned), tuple(acc_ned)
        self.update_ns = v.sim_ns

    def set_accel(self, v, acc_ned, yaw: YawRequest) -> None:
        if self.sub != Sub.ACCEL:
            self._pva_start(v, Sub.ACCEL)
            self.vel_int = (v.est.vel_ne_m_s[0], v.est.vel_ne_m_s[1], -v.climb_m_s)
        self._set_yaw(v, yaw)
        self.acc_ned = tuple(acc_ned)
        self.update_ns = v.sim_ns

    def set_angle(self, v, euler_rad, rates_frd, climb_or_thrust: float, use_thrust: bool
                  ) -> None:
        """euler_rad (roll, pitch, yaw) or None: body rates only (rates_frd, zeros when
        ignored); else the attitude with rates_frd fed forward."""
        if self.sub != Sub.ANGLE:
            self._end_takeoff(v)
            self.sub = Sub.ANGLE
            self.att_rp = (0.0, 0.0)
            if v.airborne:
                v.reset_vertical()
        self.att_euler = euler_rad
        self.att_rates = tuple(rates_frd)
        self.att_thrust = use_thrust
        self.att_value = climb_or_thrust
        self.update_ns = v.sim_ns

    def set_speed(self, v, kind: str, speed_m_s: float) -> bool:
        """DO_CHANGE_SPEED in GUIDED: for the present sub-mode (a new one starts from WPNAV_*,
        as ArduCopter's pva_control_start)."""
        if kind == "ground":
            self.speed_m_s = speed_m_s
            if self.sub == Sub.WP:
                v.start_track(v.track_dest_ne(), self.alt_goal_m, speed_m_s)
        elif kind == "climb":
            self.up_m_s = speed_m_s
        else:
            self.dn_m_s = speed_m_s
        return True

    def condition_yaw(self, v, angle_deg: float, rate_deg_s: float, direction: int,
                      relative: bool) -> None:
        self._sync_yaw_reference()
        self.auto_yaw.set_fixed(math.radians(angle_deg), math.radians(rate_deg_s), direction,
                                relative, self.ycfg.slew_max_rad_s, v.yaw_rad)

    def _sync_yaw_reference(self) -> None:
        """ArduCopter's AutoYaw keeps the attitude target as its angle in the rate modes."""
        if self.auto_yaw.mode in (YawMode.HOLD, YawMode.RATE, YawMode.PILOT_RATE):
            self.auto_yaw.yaw_rad = self.heading.shaped_rad

    def _set_yaw(self, v, y: YawRequest) -> None:
        """ModeGuided::set_yaw_state."""
        a = self.auto_yaw
        if y.use_yaw and y.relative:
            self._sync_yaw_reference()
            a.set_fixed(y.yaw_rad, 0.0, 0, True, self.ycfg.slew_max_rad_s, v.yaw_rad)
        elif y.use_yaw:
            a.set_angle_rate(wrap_pi(y.yaw_rad), y.rate_rad_s if y.use_rate else 0.0, v.yaw_rad)
        elif y.use_rate:
            a.set_rate(y.rate_rad_s, v.yaw_rad)
        else:
            a.set_default(self.ycfg.wp_yaw_behavior, v.yaw_rad)

    # ---- the step --------------------------------------------------------------------------
    def run(self, v, dt_s):
        self._refresh(v)
        timed_out = v.sim_ns - self.update_ns > self.timeout_ns
        if self.sub == Sub.ANGLE:
            self._run_angle(v, dt_s, timed_out)
            return
        if timed_out and self.sub != Sub.TAKEOFF:
            self._timeout()
        if not v.airborne and self.sub != Sub.TAKEOFF:
            self._ground(v, dt_s)
            return
        desired_vel = getattr(self, "_run_" + self.sub.value)(v, dt_s)
        self._run_yaw(v, dt_s, desired_vel)

    def _timeout(self) -> None:
        if self.sub in (Sub.VELACCEL, Sub.ACCEL, Sub.POSVELACCEL):
            self.vel_ned = self.acc_ned = (0.0, 0.0, 0.0)
            if self.sub == Sub.ACCEL:
                self.vel_int = (0.0, 0.0, 0.0)
        if self.auto_yaw.mode in (YawMode.RATE, YawMode.ANGLE_RATE):
            self.auto_yaw.set_mode(YawMode.HOLD, self.heading.shaped_rad)

    def _ground(self, v, dt_s) -> None:
        """Landed: stay down, nose where it is (ArduCopter's make_safe_ground_handling)."""
        v.command_vertical(dt_s, 0.0)
        v.hold_position(dt_s, None, (0.0, 0.0), self.speed_m_s)
        self.heading.reset(v.yaw_rad)
        v.yaw_target_rad, v.yaw_rate_cmd = v.yaw_rad, None

    def _run_takeoff(self, v, dt_s):
        v.command_vertical(dt_s, self.takeoff_alt_m)
        v.hold_position(dt_s, self.hold_ne, (0.0, 0.0), self.speed_m_s)
        if not self.takeoff_done and v.airborne \
                and v.alt_m >= self.takeoff_alt_m - v.cfg.takeoff_done_m:
            self.takeoff_done = True
            v.takeoff_in_progress = False
            v.alt_hold_m = self.takeoff_alt_m
        return (0.0, 0.0)

    def _run_wp(self, v, dt_s):
        v.fly_track(dt_s)
        return v.est.vel_ne_m_s

    def _shape_to(self, v, dt_s, dest_ne, vel_want, acc_want) -> None:
        """ArduCopter's input_pos_vel_accel_xy: the desired (pos, vel, accel) walks toward the
        target along a jerk-limited path; the position controller follows it."""
        self.pos_d, self.vel_d = advance_xy(self.pos_d, self.vel_d, self.acc_d, dt_s)
        self.acc_d = shape_pos_vel_accel_xy(dest_ne, vel_want, acc_want, self.pos_d, self.vel_d,
                                            self.acc_d, self.speed_m_s, v.cfg.wp.accel_m_s2,
                                            v.cfg.pos.jerk_m_s3, dt_s, False)
        v.hold_position(dt_s, self.pos_d, self.vel_d, self.speed_m_s, accel_ne=self.acc_d)

    def _vertical_to(self, v, dt_s, goal_m: float) -> None:
        """Approach an altitude at the sub-mode's climb/descent speeds (DO_CHANGE_SPEED may
        have slowed them; command_vertical itself moves at most WPNAV_SPEED_UP/_DN)."""
        step = goal_m - v.alt_target_m
        step = max(-self.dn_m_s * dt_s, min(self.up_m_s * dt_s, step))
        v.command_vertical(dt_s, v.alt_target_m + step)

    def _run_pos(self, v, dt_s):
        self._shape_to(v, dt_s, self.dest_ne, (0.0, 0.0), (0.0, 0.0))
        self._vertical_to(v, dt_s, self.alt_goal_m)
        return self.vel_d

    def _run_posvelaccel(self, v, dt_s):
        vel, acc = self.vel_ned[:2], self.acc_ned[:2]
        self.dest_ne, _ = advance_xy(self.dest_ne, vel, acc, dt_s)
        self.vel_ned = (vel[0] + acc[0] * dt_s, vel[1] + acc[1] * dt_s, self.vel_ned[2])
        self.alt_goal_m -= self.vel_ned[2] * dt_s
        self._shape_to(v, dt_s, self.dest_ne, self.vel_ned[:2], acc)
        self._vertical_to(v, dt_s, self.alt_goal_m)
        return self.vel_d

    def _run_velaccel(self, v, dt_s):
        vel = self.vel_ned[:2]
        self._horizontal_velocity(v, dt_s, vel, self.acc_ned[:2])
        self._climb(v, dt_s, -self.vel_ned[2])
        return vel

    def _run_accel(self, v, dt_s):
        a = self.acc_ned
        vn, ve, vd = (self.vel_int[i] + a[i] * dt_s for i in range(3))
        k = min(1.0, self.speed_m_s / max(math.hypot(vn, ve), 1e-9))
        self.vel_int = (vn * k, ve * k, vd)
        self._horizontal_velocity(v, dt_s, self.vel_int[:2], a[:2])
        self._climb(v, dt_s, -self.vel_int[2])
        return self.vel_int[:2]

    @staticmethod
    def _horizontal_velocity(v, dt_s, vel, acc) -> None:
        """A velocity target, shaped, with a position target moving along (velocity 0 brakes
        and holds where it stops); not limited to WPNAV_SPEED, as ArduCopter's."""
        v.hold_position(dt_s, None, vel, max(v.cfg.wp.speed_m_s, math.hypot(*vel)),
                        accel_ne=acc)

    def _climb(self, v, dt_s, climb_m_s: float) -> None:
        climb = max(-self.dn_m_s, min(self.up_m_s, climb_m_s))
        if climb == 0.0:
            v.command_vertical(dt_s, v.alt_hold_m)
        else:
            v.command_climb(dt_s, climb)

    def _run_yaw(self, v, dt_s, desired_vel) -> None:
        a = self.auto_yaw
        stick = v.pilot_sticks_rpy()[2]
        if not self.options & OPT_IGNORE_PILOT_YAW and abs(stick) > PILOT_YAW_DEADZONE:
            a.set_mode(YawMode.PILOT_RATE, v.yaw_rad)
            a.rate_rad_s = stick * v.cfg.pilot_y_rate_rad_s
        elif a.mode == YawMode.PILOT_RATE:
            a.rate_rad_s = 0.0
        tgt, ff, angle = a.target(dt_s, self.heading.shaped_rad, desired_vel, self.speed_m_s,
                                  v.est.vel_ne_m_s)
        v.yaw_target_rad, v.yaw_rate_cmd = self.heading.update(dt_s, self.ycfg, v.yaw_rad, tgt,
                                                               ff, angle)

    # ---- ANGLE -----------------------------------------------------------------------------
    def _run_angle(self, v, dt_s, timed_out: bool) -> None:
        if timed_out:
            # ArduCopter: level at the present heading target, no rates, climb 0
            self.att_euler = (0.0, 0.0, self.heading.shaped_rad)
            self.att_rates = (0.0, 0.0, 0.0)
            self.att_thrust, self.att_value = False, 0.0
        value = self.att_value
        if not self.att_thrust:
            value = max(-self.dn_m_s, min(self.up_m_s, value))
        if not v.airborne and value <= 0.0:
            self._ground(v, dt_s)
            return
        lim = v.cfg.angle_max_rad
        if self.att_euler is None:
            # body rates: roll and pitch targets integrate them, yaw is a rate
            p, q, r = self.att_rates
            self.att_rp = (max(-lim, min(lim, self.att_rp[0] + p * dt_s)),
                           max(-lim, min(lim, self.att_rp[1] + q * dt_s)))
            v.command_attitude(*self.att_rp)
            tgt, ff, angle = self.heading.shaped_rad, r, False
        else:
            roll, pitch, yaw = self.att_euler
            self.att_rp = (max(-lim, min(lim, roll)), max(-lim, min(lim, pitch)))
            v.command_attitude(*self.att_rp)
            tgt, ff, angle = yaw, self.att_rates[2], True
        # input_quaternion: the attitude controller's rate limit, not ATC_SLEW_YAW
        v.yaw_target_rad, v.yaw_rate_cmd = self.heading.update(
            dt_s, self.ycfg, v.yaw_rad, tgt, ff, angle, rate_max_rad_s=self.ycfg.rate_max_rad_s)
        if self.att_thrust:
            v.command_throttle(max(0.0, value))
        elif value == 0.0:
            v.command_vertical(dt_s, v.alt_hold_m)
        else:
            v.command_climb(dt_s, value)
