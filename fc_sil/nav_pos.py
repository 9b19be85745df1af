"""Horizontal position controller: position, velocity and acceleration targets -> lean angles.

ArduCopter 4.6's AC_PosControl, horizontal half, at the outer-loop rate:

  targets: position, desired velocity and desired acceleration (NE), either handed in as a
  kinematically consistent triple (``set_pos_vel_accel``: the waypoint S-curve, a fixed hold
  point) or shaped here from a velocity command (``input_vel_accel``: the desired velocity
  moves toward the command along a jerk-limited path, PSC_JERK_XY and WPNAV_ACCEL, and the
  position target integrates it);
  position error --sqrt controller (PSC_POSXY_P, limited by the correction acceleration;
  the error itself is capped where the correction would exceed the correction speed)-->
  velocity correction, + desired velocity = velocity target;
  velocity error --PID (PSC_VELXY_P/I/D/IMAX/FF, error low-pass FLTE, derivative low-pass
  FLTD)--> acceleration correction, + desired acceleration = acceleration target,
  limited to the lean angle PSC_ANGLE_MAX (0: ANGLE_MAX) allows, the cross-track part first;
  acceleration -> roll/pitch in the heading frame:
  pitch = -atan(a_forward / g) (nose down to go forward), roll = atan(a_right cos(pitch) / g).

The integrator does not grow in the direction the acceleration limit clipped last step.
When the estimate resets (pos_est.py: a GNSS glitch timed out), ``shift`` moves the targets
by the reset's jump, so the errors the controller sees, and the vehicle, do not jump
(AC_PosControl::handle_ekf_xy_reset keeps the target at the estimate plus the old error).
Frames: NE metres about the estimator origin; m/s; m/s^2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .nav_kinematics import (advance_xy, inv_sqrt_controller, limit_accel_xy, limit_length,
                             shape_vel_accel_xy, sqrt_controller_xy)

G_M_S2 = 9.80665


@dataclass
class PosGains:
    pos_p: float = 1.0            # PSC_POSXY_P [1/s]
    vel_p: float = 2.0            # PSC_VELXY_P [1/s]
    vel_i: float = 1.0            # PSC_VELXY_I [1/s^2]
    vel_d: float = 0.5            # PSC_VELXY_D [-]
    vel_imax_m_s2: float = 10.0   # PSC_VELXY_IMAX / 100
    vel_ff: float = 0.0           # PSC_VELXY_FF [1/s]
    vel_flte_hz: float = 5.0      # PSC_VELXY_FLTE; 0 = no filter
    vel_fltd_hz: float = 5.0      # PSC_VELXY_FLTD; 0 = no filter
    jerk_m_s3: float = 5.0        # PSC_JERK_XY (limited by the attitude's angular accel)
    accel_m_s2: float = 2.5       # WPNAV_ACCEL / 100: shaping and correction acceleration
    speed_m_s: float = 10.0       # WPNAV_SPEED / 100: correction speed limit
    angle_max_rad: float = math.radians(30.0)   # PSC_ANGLE_MAX, or ANGLE_MAX when 0


def _alpha(cutoff_hz: float, dt_s: float) -> float:
    """First-order low-pass gain per step; a cutoff of 0 passes the input through."""
    if cutoff_hz <= 0.0:
        return 1.0
    rc = 1.0 / (2.0 * math.pi * cutoff_hz)
    return dt_s / (dt_s + rc)


class PosController:
    """``reset`` when taking over; each step one of ``set_pos_vel_accel`` or
    ``input_vel_accel``, then ``update``."""

    def __init__(self, gains: PosGains | None = None):
        self.g = gains or PosGains()
        self.pos_target = (0.0, 0.0)      # [m]
        self.vel_desired = (0.0, 0.0)     # feed-forward velocity [m/s]
        self.accel_desired = (0.0, 0.0)   # feed-forward acceleration [m/s^2]
        self.vel_target = (0.0, 0.0)      # desired + position correction [m/s]
        self.accel_target = (0.0, 0.0)    # after the PID and the lean limit [m/s^2]
        self.limit = (0.0, 0.0)           # last acceleration clipped by the lean limit
        self.last_update_ns = None        # sim time of the last step (None: never run)
        self.pos_error_m = 0.0
        self._err_f = None                # filtered velocity error
        self._deriv = (0.0, 0.0)
        self._integ = (0.0, 0.0)

    def is_active(self, now_ns: int, timeout_ns: int) -> bool:
        """Run within timeout_ns (AC_PosControl re-initialises a controller that was not)."""
        return self.last_update_ns is not None and now_ns - self.last_update_ns <= timeout_ns

    def reset(self, pos_ne_m, vel_ne_m_s, accel_ne_m_s2=(0.0, 0.0)) -> None:
        """Take over at the present position and velocity, keeping the acceleration (lean)
        now commanded, so the hand-over makes no step."""
        self.pos_target = (float(pos_ne_m[0]), float(pos_ne_m[1]))
        self.vel_desired = self.vel_target = (float(vel_ne_m_s[0]), float(vel_ne_m_s[1]))
        ax, ay, _ = limit_length(accel_ne_m_s2[0], accel_ne_m_s2[1], self.g.accel_m_s2)
        self.accel_desired = (ax, ay)
        self.accel_target = (float(accel_ne_m_s2[0]), float(accel_ne_m_s2[1]))
        self.limit = (0.0, 0.0)
        self._err_f = None
        self._deriv = (0.0, 0.0)
        self._integ = (self.accel_target[0] - ax, self.accel_target[1] - ay)

    def shift(self, dpos_ne_m, dvel_ne_m_s=(0.0, 0.0)) -> None:
        """The estimate jumped by dpos (and dvel): move the targets with it."""
        self.pos_target = shifted(self.pos_target, dpos_ne_m)
        self.vel_desired = shifted(self.vel_desired, dvel_ne_m_s)
        self.vel_target = shifted(self.vel_target, dvel_ne_m_s)

    def set_pos_vel_accel(self, pos_ne_m, vel_ne_m_s, accel_ne_m_s2) -> None:
        """Targets from a path that is already kinematically shaped (or a fixed point)."""
        self.pos_target = (float(pos_ne_m[0]), float(pos_ne_m[1]))
        self.vel_desired = (float(vel_ne_m_s[0]), float(vel_ne_m_s[1]))
        self.accel_desired = (float(accel_ne_m_s2[0]), float(accel_ne_m_s2[1]))

    def input_vel_accel(self, dt_s: float, vel_ne_m_s, accel_ne_m_s2, speed_max_m_s: float,
                        accel_max_m_s2: float | None = None) -> None:
        """Shape the desired velocity toward a commanded velocity (jerk-limited, at most
        accel_max_m_s2, default WPNAV_ACCEL), moving the position target along with it."""
        g = self.g
        self._advance_targets(dt_s)
        vx, vy, _ = limit_length(vel_ne_m_s[0], vel_ne_m_s[1], speed_max_m_s)
        self.accel_desired = shape_vel_accel_xy((vx, vy), accel_ne_m_s2, self.vel_desired,
                                                self.accel_desired,
                                                accel_max_m_s2 or g.accel_m_s2,
                                                g.jerk_m_s3, dt_s, False)

    def _advance_targets(self, dt_s: float) -> None:
        """Move the targets on by dt, except into the direction the lean limit clipped."""
        p, v = advance_xy(self.pos_target, self.vel_desired, self.accel_desired, dt_s)
        lx, ly = self.limit
        if lx or ly:
            ex, ey = self.pos_target[0], self.pos_target[1]
            dpx, dpy = p[0] - ex, p[1] - ey
            if dpx * lx + dpy * ly > 0.0:
                p = self.pos_target
            dvx = self.accel_desired[0] * dt_s
            dvy = self.accel_desired[1] * dt_s
            if dvx * lx + dvy * ly > 0.0:
                v = self.vel_desired
        self.pos_target, self.vel_desired = p, v

    def update(self, dt_s: float, pos_ne_m, vel_ne_m_s, yaw_rad: float = 0.0,
               speed_max_m_s: float | None = None, accel_max_m_s2: float | None = None,
               err_max_m: float | None = None) -> tuple[float, float]:
        """One controller step; returns (roll_rad, pitch_rad) for the attitude controller.
        The position correction is limited to speed_max_m_s (default WPNAV_SPEED) and
        accel_max_m_s2 (default WPNAV_ACCEL); err_max_m overrides the error cap."""
        g = self.g
        speed = g.speed_m_s if speed_max_m_s is None else speed_max_m_s
        accel = accel_max_m_s2 or g.accel_m_s2
        # position -> velocity correction; the error is capped where the correction would
        # exceed the correction speed (the target is pulled toward the vehicle there)
        ex = self.pos_target[0] - pos_ne_m[0]
        ey = self.pos_target[1] - pos_ne_m[1]
        if err_max_m is None:
            err_max_m = inv_sqrt_controller(speed, g.pos_p, accel) if speed > 0.0 else 0.0
        ex, ey, capped = limit_length(ex, ey, err_max_m)
        if capped:
            self.pos_target = (pos_ne_m[0] + ex, pos_ne_m[1] + ey)
        self.pos_error_m = math.hypot(ex, ey)
        cx, cy = sqrt_controller_xy(ex, ey, g.pos_p, accel, dt_s)
        vt = (cx + self.vel_desired[0], cy + self.vel_desired[1])
        self.vel_target = vt
        ax, ay = self._vel_pid(dt_s, vt, vel_ne_m_s)
        ax += self.accel_desired[0]
        ay += self.accel_desired[1]
        a_lim = G_M_S2 * math.tan(g.angle_max_rad)
        ax, ay, clipped = limit_accel_xy(self.vel_desired, ax, ay, a_lim)
        self.limit = (ax, ay) if clipped else (0.0, 0.0)
        self.accel_target = (ax, ay)
        return accel_to_lean(ax, ay, yaw_rad, g.angle_max_rad)

    def _vel_pid(self, dt_s: float, vel_target, vel) -> tuple[float, float]:
        g = self.g
        ex, ey = vel_target[0] - vel[0], vel_target[1] - vel[1]
        if self._err_f is None:
            self._err_f = (ex, ey)
            self._deriv = (0.0, 0.0)
        else:
            k = _alpha(g.vel_flte_hz, dt_s)
            fx = self._err_f[0] + (ex - self._err_f[0]) * k
            fy = self._err_f[1] + (ey - self._err_f[1]) * k
            kd = _alpha(g.vel_fltd_hz, dt_s)
            dx, dy = (fx - self._err_f[0]) / dt_s, (fy - self._err_f[1]) / dt_s
            self._deriv = (self._deriv[0] + (dx - self._deriv[0]) * kd,
                           self._deriv[1] + (dy - self._deriv[1]) * kd)
            self._err_f = (fx, fy)
        fx, fy = self._err_f
        # the integrator may not grow toward the direction the lean limit clipped
        dix, diy = fx * g.vel_i * dt_s, fy * g.vel_i * dt_s
        lx, ly = self.limit
        if dix * lx + diy * ly > 0.0:
            dix = diy = 0.0
        ix, iy, _ = limit_length(self._integ[0] + dix, self._integ[1] + diy, g.vel_imax_m_s2)
        self._integ = (ix, iy)
        return (g.vel_p * fx + ix + g.vel_d * self._deriv[0] + g.vel_ff * vel_target[0],
                g.vel_p * fy + iy + g.vel_d * self._deriv[1] + g.vel_ff * vel_target[1])


def shifted(ne, d_ne) -> tuple[float, float]:
    """A NE point moved by d_ne (an estimate reset's jump)."""
    return (ne[0] + d_ne[0], ne[1] + d_ne[1])


def accel_to_lean(an: float, ae: float, yaw_rad: float, angle_max_rad: float
                  ) -> tuple[float, float]:
    """NE acceleration -> (roll, pitch) [rad] in the heading frame, limited to angle_max."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    a_fwd = an * c + ae * s
    a_right = -an * s + ae * c
    pitch = -math.atan2(a_fwd, G_M_S2)
    roll = math.atan2(a_right * math.cos(pitch), G_M_S2)
    lim = angle_max_rad
    return max(-lim, min(lim, roll)), max(-lim, min(lim, pitch))


def lean_to_accel(roll_rad: float, pitch_rad: float, yaw_rad: float) -> tuple[float, float]:
    """Inverse of ``accel_to_lean``: the NE acceleration a level-height lean gives."""
    a_fwd = -G_M_S2 * math.tan(pitch_rad)
    a_right = G_M_S2 * math.tan(roll_rad) / max(1e-6, math.cos(pitch_rad))
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return a_fwd * c - a_right * s, a_fwd * s + a_right * c
