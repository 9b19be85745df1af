"""Horizontal position/velocity controller: target position and/or velocity -> lean angles.

ArduCopter's AC_PosControl in its simplest faithful form, at the outer-loop rate:

  position error --sqrt controller (PSC_POSXY_P, limited by WPNAV_ACCEL)--> velocity target
  + velocity feed-forward, limited to the speed limit, then *shaped*: the velocity target
  moves toward its goal at most WPNAV_ACCEL per second (the shaped change is the
  acceleration feed-forward);
  velocity error --PID (PSC_VELXY_P/I/D)--> acceleration target (NE), limited to the lean
  angle ANGLE_MAX can give; acceleration -> roll/pitch in the heading frame:
  pitch = -atan(a_forward / g) (nose down to go forward), roll = atan(a_right / g).

The sqrt controller is linear (gain P) near the target and follows the braking curve
v = sqrt(2 a d) far from it, so a distant target is approached at the speed limit and
decelerated at WPNAV_ACCEL rather than overshot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

G_M_S2 = 9.80665


@dataclass
class PosGains:
    pos_p: float = 1.0          # PSC_POSXY_P [1/s]
    vel_p: float = 2.0          # PSC_VELXY_P [1/s]
    vel_i: float = 1.0          # PSC_VELXY_I [1/s^2]
    vel_d: float = 0.25         # PSC_VELXY_D [-]
    accel_m_s2: float = 2.5     # WPNAV_ACCEL / 100
    angle_max_rad: float = math.radians(30.0)


def sqrt_controller(error: float, p: float, accel: float) -> float:
    """ArduPilot's sqrt controller: P near zero, sqrt(2 a |e|) braking curve beyond."""
    if accel <= 0.0 or p <= 0.0:
        return error * p
    linear = accel / (p * p)          # where the two curves meet with equal slope
    if abs(error) <= linear:
        return error * p
    s = math.sqrt(2.0 * accel * (abs(error) - linear / 2.0))
    return s if error > 0 else -s


def _limit2(x: float, y: float, lim: float) -> tuple[float, float]:
    n = math.hypot(x, y)
    if n > lim > 0.0:
        k = lim / n
        return x * k, y * k
    return x, y


class PosController:
    """Call ``reset`` when taking over, then ``update`` every outer-loop step."""

    def __init__(self, gains: PosGains | None = None):
        self.g = gains or PosGains()
        self.vel_target = [0.0, 0.0]     # shaped velocity target (NE) [m/s]
        self.accel_target = [0.0, 0.0]
        self.integ = [0.0, 0.0]
        self.prev_vel_err = None
        self.pos_error_m = 0.0

    def reset(self, vel_ne_m_s) -> None:
        """Take over smoothly from the present velocity."""
        self.vel_target = [vel_ne_m_s[0], vel_ne_m_s[1]]
        self.integ = [0.0, 0.0]
        self.prev_vel_err = None

    def update(self, dt_s: float, pos_ne_m, vel_ne_m_s, *, target_pos=None,
               target_vel=(0.0, 0.0), speed_max_m_s: float = 10.0, yaw_rad: float = 0.0
               ) -> tuple[float, float]:
        """One step; returns (roll_rad, pitch_rad) for the attitude controller."""
        g = self.g
        vx, vy = target_vel
        if target_pos is not None:
            ex, ey = target_pos[0] - pos_ne_m[0], target_pos[1] - pos_ne_m[1]
            d = math.hypot(ex, ey)
            self.pos_error_m = d
            if d > 1e-6:
                s = sqrt_controller(d, g.pos_p, g.accel_m_s2)
                vx += ex / d * s
                vy += ey / d * s
        else:
            self.pos_error_m = 0.0
        vx, vy = _limit2(vx, vy, speed_max_m_s)
        # shape: the target velocity changes at most accel_m_s2
        dvx, dvy = vx - self.vel_target[0], vy - self.vel_target[1]
        dvx, dvy = _limit2(dvx, dvy, g.accel_m_s2 * dt_s)
        self.vel_target[0] += dvx
        self.vel_target[1] += dvy
        ff = (dvx / dt_s, dvy / dt_s) if dt_s > 0 else (0.0, 0.0)
        # velocity PID
        ex, ey = self.vel_target[0] - vel_ne_m_s[0], self.vel_target[1] - vel_ne_m_s[1]
        if self.prev_vel_err is None or dt_s <= 0:
            dx = dy = 0.0
        else:
            dx = (ex - self.prev_vel_err[0]) / dt_s
            dy = (ey - self.prev_vel_err[1]) / dt_s
        self.prev_vel_err = (ex, ey)
        a_lim = G_M_S2 * math.tan(g.angle_max_rad)
        ax = ff[0] + g.vel_p * ex + self.integ[0] + g.vel_d * dx
        ay = ff[1] + g.vel_p * ey + self.integ[1] + g.vel_d * dy
        lim_ax, lim_ay = _limit2(ax, ay, a_lim)
        # integrate only while the output is not limited (no wind-up against the lean limit)
        if (lim_ax, lim_ay) == (ax, ay):
            self.integ[0] += g.vel_i * ex * dt_s
            self.integ[1] += g.vel_i * ey * dt_s
            self.integ = list(_limit2(self.integ[0], self.integ[1], a_lim * 0.5))
        self.accel_target = [lim_ax, lim_ay]
        return accel_to_lean(lim_ax, lim_ay, yaw_rad, g.angle_max_rad)


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
