"""NavHelpers: the vehicle's navigation outputs, shared by every flight mode.

A mixin of fc_sil/vehicle.py's Vehicle (it uses the vehicle's estimator, controllers and C
core): modes call these instead of touching the core, so all modes share one position
controller (nav_pos.py), one waypoint navigator (nav_wp.py) and one vertical channel, and the
pilot's sticks (pilot.py) mean the same thing in every mode that reads them.

Vertical channel: ``command_vertical`` moves an altitude target at WPNAV_SPEED_UP/_DN and
hands it to the C core's altitude controller; ``command_climb`` asks the core for a climb
rate; ``land_descent`` descends at WPNAV_SPEED_DN above LAND_ALT_LOW and LAND_SPEED below and
reports touchdown from the core's land detector. Horizontal: ``hold_position`` runs the
position controller (only once airborne: on the ground its integrators would wind up against
friction) and leaves lean angles for the step's single attitude command; ``start_track`` /
``fly_track`` fly a straight leg along its S-curve (nav_wp.py); ``fly_loiter`` turns the
sticks into shaped targets (nav_loiter.py). As AC_PosControl, a position controller that was
not run for a few steps starts again from the vehicle's present position and velocity.

Estimate resets: ``follow_xy_reset`` runs each step after the estimator; when the estimate
reset (pos_est.py: GNSS that failed its gate for the retry time is taken as it is), the
position controller's targets and the mode's "hold here" points move by the same jump, so
the vehicle stays where it is and holds on the new frame (ArduCopter 4.6: AC_PosControl's
handle_ekf_xy_reset, for Loiter, PosHold, Brake, Land, take-off and Guided velocity
control). Points given as coordinates (waypoints, a Guided destination, home) stay: they
name a place, and the reset has made the estimate of where that place is better or worse,
not moved it. Our vertical estimate (the C core's baro + accel filter) never resets in
flight, so there is no vertical counterpart.
"""

from __future__ import annotations

import dataclasses
import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from .nav_loiter import CORRECTION_POS_M, CORRECTION_SPEED_M_S, LoiterNav
from .nav_pos import lean_to_accel
from .nav_wp import WpSpeeds

# the position controller counts as running if it ran within this many outer steps
_ACTIVE_STEPS = 5


class NavHelpers:
    _xy_resets_seen = 0     # the estimator's xy_reset_count already followed

    def follow_xy_reset(self) -> None:
        """Move the horizontal targets by the estimate's reset, once per reset."""
        est = self.est
        if est.xy_reset_count == self._xy_resets_seen:
            return
        self._xy_resets_seen = est.xy_reset_count
        self.pos_ctl.shift(est.xy_reset_ne_m, est.xy_reset_vel_ne_m_s)
        self.mode.follow_xy_reset(self, est.xy_reset_ne_m)

    def _wp_speeds(self, speed_m_s: float | None) -> WpSpeeds:
        sp = self.cfg.wp
        if speed_m_s:
            return dataclasses.replace(sp, speed_m_s=speed_m_s)
        return sp

    def reset_vertical(self) -> None:
        self.alt_target_m = self.alt_m if self.airborne else min(self.alt_m, 0.0)
        self.alt_hold_m = self.alt_m if self.airborne else 0.0

    def reset_horizontal(self) -> None:
        """Position control takes over here, at the present velocity and commanded lean."""
        self.pos_ctl.reset(self.est.pos_ne_m, self.est.vel_ne_m_s,
                           lean_to_accel(self.cmd_roll, self.cmd_pitch, self.yaw_rad))
        self.pos_ctl.last_update_ns = self.sim_ns

    def command_attitude(self, roll_rad: float, pitch_rad: float) -> None:
        self.cmd_roll, self.cmd_pitch = roll_rad, pitch_rad

    def command_throttle(self, throttle: float) -> None:
        self.core.set_throttle(min(1.0, max(0.0, throttle)))
        self.alt_target_m = self.alt_hold_m = self.alt_m

    def command_vertical(self, dt_s: float, goal_m: float) -> None:
        """Hold/approach an altitude, moving the target at WPNAV_SPEED_UP/_DN."""
        sp = self.cfg.wp
        if not self.airborne and goal_m <= 0.0:
            self.alt_target_m = goal_m
        else:
            err = goal_m - self.alt_target_m
            self.alt_target_m += max(-sp.dn_m_s * dt_s, min(sp.up_m_s * dt_s, err))
        self.core.set_altitude_target(self.alt_target_m)

    def command_climb(self, dt_s: float, climb_m_s: float) -> None:
        self.core.set_climb_rate(climb_m_s)
        self.alt_target_m = self.alt_hold_m = self.alt_m

    def land_descent(self, dt_s: float) -> bool:
        """LAND's vertical channel; True once touched down (the core's land detector)."""
        self.landing = True
        if self.armed and not self.airborne and self.spool != 2:
            return True
        fast = self.alt_m > self.cfg.land_alt_low_m
        speed = self.cfg.wp.dn_m_s if fast else self.cfg.land_speed_m_s
        self.core.set_climb_rate(-speed)
        self.alt_target_m = self.alt_hold_m = 0.0
        return False

    def _pos_ctl_ready(self) -> bool:
        """False (and the controller reset, level) while there is nothing to control."""
        pc = self.pos_ctl
        if not self.airborne or not self.position_ok():
            pc.reset(self.est.pos_ne_m, self.est.vel_ne_m_s if self.airborne else (0.0, 0.0))
            pc.last_update_ns = None
            self.command_attitude(0.0, 0.0)
            return False
        if not pc.is_active(self.sim_ns, _ACTIVE_STEPS * self.nav_period_ns):
            self.reset_horizontal()
        pc.last_update_ns = self.sim_ns
        return True

    def hold_position(self, dt_s: float, target_ne, vel_ne, speed_m_s: float,
                      accel_ne=(0.0, 0.0), *, shape_accel_m_s2: float | None = None) -> None:
        """target_ne: a point (with its velocity and acceleration fed forward) to follow as
        given; None: fly the velocity vel_ne, shaped (PSC_JERK_XY, at most shape_accel_m_s2,
        default WPNAV_ACCEL) and held by a position target that moves along with it."""
        if not self._pos_ctl_ready():
            return
        pc = self.pos_ctl
        if target_ne is None:
            pc.input_vel_accel(dt_s, vel_ne, accel_ne, speed_m_s, shape_accel_m_s2)
        else:
            pc.set_pos_vel_accel(target_ne, vel_ne, accel_ne)
        roll, pitch = pc.update(dt_s, self.est.pos_ne_m, self.est.vel_ne_m_s, self.yaw_rad,
                                speed_m_s, shape_accel_m_s2)
        self.command_attitude(roll, pitch)

    def fly_loiter(self, dt_s: float, nav: LoiterNav, roll_in: float, pitch_in: float) -> None:
        """LOITER's horizontal channel: sticks (-1..1) -> AC_Loiter targets -> lean."""
        if not self._pos_ctl_ready():
            nav.reset((0.0, 0.0), (0.0, 0.0))
            return
        pc = self.pos_ctl
        pos, vel, acc = nav.update(dt_s, pc.pos_target, roll_in, pitch_in, self.yaw_rad)
        pc.set_pos_vel_accel(pos, vel, acc)
        roll, pitch = pc.update(dt_s, self.est.pos_ne_m, self.est.vel_ne_m_s, self.yaw_rad,
                                CORRECTION_SPEED_M_S, nav.cfg.accel_max_m_s2, CORRECTION_POS_M)
        self.command_attitude(roll, pitch)

    def start_track(self, dest_ne, alt_m: float, speed_m_s: float | None) -> None:
        """A straight leg to dest_ne at alt_m from where the position target is now (the
        vehicle's position when the controller is not running), at the speed the target
        already has along the leg."""
        self.wp.sp = self._wp_speeds(speed_m_s or self.speed_override_m_s)
        start_alt = self.alt_target_m if self.airborne else self.alt_m
        pc = self.pos_ctl
        active = self.airborne and pc.is_active(self.sim_ns, _ACTIVE_STEPS * self.nav_period_ns)
        start = pc.pos_target if active else self.est.pos_ne_m
        speed = 0.0
        if active:
            dn, de = dest_ne[0] - start[0], dest_ne[1] - start[1]
            d = math.sqrt(dn * dn + de * de + (alt_m - start_alt) ** 2)
            if d > 1e-6:
                speed = max(0.0, (pc.vel_desired[0] * dn + pc.vel_desired[1] * de) / d)
        self.wp.set_destination(start, start_alt, dest_ne, alt_m, speed)

    def fly_track(self, dt_s: float) -> bool:
        """Follow the active track; True when its destination is reached."""
        tp, tv, ta, talt = self.wp.update(dt_s, self.est.pos_ne_m, self.alt_m,
                                          self.est.vel_ne_m_s, self.climb_m_s)
        self.hold_position(dt_s, tp, tv, self.wp.sp.speed_m_s, ta)
        self.alt_target_m = talt
        self.alt_hold_m = self.wp.dest[2]
        self.core.set_altitude_target(talt)
        if not self.airborne and talt > 0.0:
            self.takeoff_in_progress = True
        return self.wp.reached(self.est.pos_ne_m, self.alt_m)

    def track_dest_ne(self):
        return self.wp.dest[0], self.wp.dest[1]

    def face_track(self, rtl: bool) -> None:
        b = self.wp.bearing_rad
        behave = self.cfg.wp_yaw_behavior
        if b is None or behave == 0 or (behave == 2 and rtl):
            return
        self.yaw_target_rad = b

    def hold_heading(self) -> None:
        self.yaw_rate_cmd = None

    # ---- pilot ----------------------------------------------------------------------------

    def _pilot_fresh(self) -> bool:
        return self.pilot.fresh(self.cfg.rc_fs_timeout_s)

    def pilot_sticks_rpy(self) -> tuple[float, float, float]:
        if not self._pilot_fresh():
            return 0.0, 0.0, 0.0
        return self.pilot.roll, self.pilot.pitch, self.pilot.yaw

    def pilot_throttle_stick(self) -> float:
        """0..1; 0 without fresh pilot input (throttle down)."""
        return self.pilot.throttle if self._pilot_fresh() else 0.0

    def pilot_attitude(self) -> None:
        r, p, y = self.pilot_sticks_rpy()
        a = self.cfg.angle_max_rad
        self.command_attitude(r * a, p * a)
        self.pilot_yaw(y)

    def pilot_yaw(self, yaw_in: float) -> None:
        if abs(yaw_in) > 0.05:
            self.yaw_rate_cmd = yaw_in * self.cfg.pilot_y_rate_rad_s
            self.yaw_target_rad = self.yaw_rad
        else:
            self.yaw_rate_cmd = None

    def pilot_throttle(self) -> float:
        """STABILIZE: stick centre = hover throttle (ArduCopter's throttle curve)."""
        z = self.pilot_throttle_stick()
        h = self.cfg.hover_throttle
        return z / 0.5 * h if z <= 0.5 else h + (z - 0.5) / 0.5 * (1.0 - h)

    def pilot_vertical(self, dt_s: float) -> None:
        """ALT_HOLD/LOITER: stick = climb rate outside a 10 % dead zone, centre = hold.
        Without pilot input the stick counts as centred (hold)."""
        z = self.pilot.throttle if self._pilot_fresh() else 0.5
        if z > 0.6:
            self.command_climb(dt_s, (z - 0.6) / 0.4 * self.cfg.pilot_speed_up_m_s)
        elif z < 0.4:
            self.command_climb(dt_s, (z - 0.4) / 0.4 * self.cfg.pilot_speed_dn_m_s)
        else:
            self.command_vertical(dt_s, self.alt_hold_m)

    def _read_mode_switch(self) -> None:
        """FLTMODE_CH's switch position selects FLTMODE1..6 (rc_input.py), once per move."""
        mode = self.mode_switch.update(
            self.pilot.rc, self.pilot.channels_us,
            lambda i: self.pilot.channel_fresh(i, self.cfg.rc_fs_timeout_s), self.sim_ns * 1e-9)
        if mode is not None and mode != self.mode.number:
            reason = self._change_mode(mode)
            if reason:
                self.statustext(mav.MAV_SEVERITY_WARNING, reason)
