"""Kinematic shaping helpers of the position controller (the facts of ArduPilot's AP_Math control).

Every target the position controller follows is a (position, velocity, acceleration) triple
that changes no faster than the configured jerk: a new position or velocity is approached
along a jerk-limited path instead of being handed to the controller as a step. Three verbs:

* ``sqrt_controller``: P near zero, the braking curve sqrt(2 a |e|) beyond, and never a
  correction that would cross zero within one step;
* ``shape_vel_accel_xy``: move the acceleration target toward what corrects a velocity
  error (gain jerk/accel, so the correction reaches full acceleration in accel/jerk seconds),
  limited to accel_max, changed at most jerk*dt per step;
* ``shape_pos_vel_accel_xy``: the same one level up: a position error becomes a velocity
  correction through a sqrt controller with half the acceleration and half the gain (the
  half leaves room for the velocity stage, so the path neither overshoots nor oscillates).

``advance_xy`` moves a (pos, vel, accel) triple forward by dt. Vectors are (north, east)
tuples in metres, m/s and m/s^2.
"""

from __future__ import annotations

import math


def sqrt_controller(error: float, p: float, accel: float, dt_s: float = 0.0) -> float:
    """Correction rate for ``error``: linear (gain p) within accel/p^2 of zero, then
    sqrt(2 accel (|e| - accel/(2 p^2))); limited to |e|/dt so one step never passes zero."""
    if accel <= 0.0:
        out = error * p
    elif p <= 0.0:
        out = math.copysign(math.sqrt(2.0 * accel * abs(error)), error) if error else 0.0
    else:
        linear = accel / (p * p)
        if abs(error) > linear:
            out = math.copysign(math.sqrt(2.0 * accel * (abs(error) - linear / 2.0)), error)
        else:
            out = error * p
    if dt_s > 0.0:
        lim = abs(error) / dt_s
        out = max(-lim, min(lim, out))
    return out


def inv_sqrt_controller(output: float, p: float, accel: float) -> float:
    """The error for which ``sqrt_controller`` gives ``output`` (a stopping distance)."""
    if accel > 0.0 and p <= 0.0:
        return output * output / (2.0 * accel)
    if accel <= 0.0:
        return output / p if p > 0.0 else 0.0
    if abs(output) < accel / p:
        return output / p
    d = accel / (2.0 * p * p) + output * output / (2.0 * accel)
    return math.copysign(d, output)


def sqrt_controller_xy(ex: float, ey: float, p: float, accel: float, dt_s: float
                       ) -> tuple[float, float]:
    n = math.hypot(ex, ey)
    if n <= 0.0:
        return 0.0, 0.0
    k = sqrt_controller(n, p, accel, dt_s) / n
    return ex * k, ey * k


def limit_length(x: float, y: float, lim: float) -> tuple[float, float, bool]:
    n = math.hypot(x, y)
    if lim > 0.0 and n > lim:
        k = lim / n
        return x * k, y * k, True
    return x, y, False


def limit_accel_xy(vel, ax: float, ay: float, accel_max: float) -> tuple[float, float, bool]:
    """Limit |a| to accel_max keeping the cross-track part first (the part that holds the
    track), the along-track part gets what is left; a plain length limit when not moving."""
    if accel_max <= 0.0 or ax * ax + ay * ay <= accel_max * accel_max:
        return ax, ay, False
    vn = math.hypot(vel[0], vel[1])
    if vn <= 0.0:
        return limit_length(ax, ay, accel_max)
    ux, uy = vel[0] / vn, vel[1] / vn
    along = ax * ux + ay * uy
    cx, cy = ax - along * ux, ay - along * uy
    cx, cy, clipped = limit_length(cx, cy, accel_max)
    if clipped:
        along = 0.0
    else:
        rest = math.sqrt(max(0.0, accel_max * accel_max - cx * cx - cy * cy))
        along = max(-rest, min(rest, along))
    return cx + along * ux, cy + along * uy, True


def shape_accel_xy(want, accel, jerk_max: float, dt_s: float) -> tuple[float, float]:
    """Move ``accel`` toward ``want`` by at most jerk_max * dt."""
    dx, dy, _ = limit_length(want[0] - accel[0], want[1] - accel[1], jerk_max * dt_s)
    return accel[0] + dx, accel[1] + dy


def shape_vel_accel_xy(vel_want, accel_want, vel, accel, accel_max: float, jerk_max: float,
                       dt_s: float, limit_total: bool) -> tuple[float, float]:
    """New acceleration target driving ``vel`` toward ``vel_want`` (+ ``accel_want``)."""
    kpa = jerk_max / accel_max
    ax, ay = sqrt_controller_xy(vel_want[0] - vel[0], vel_want[1] - vel[1], kpa, jerk_max,
                                dt_s)
    ax, ay, _ = limit_accel_corner_xy(vel_want, ax, ay, accel_max)
    ax, ay = ax + accel_want[0], ay + accel_want[1]
    if limit_total:
        ax, ay, _ = limit_length(ax, ay, accel_max)
    return shape_accel_xy((ax, ay), accel, jerk_max, dt_s)


_CORNER_RATIO = 1.0 / math.sqrt(2.0)   # cross-track share kept when the along-track part dominates


def limit_accel_corner_xy(vel, ax: float, ay: float, accel_max: float
                          ) -> tuple[float, float, bool]:
    vn = math.hypot(vel[0], vel[1])
    if vn <= 0.0:
        return limit_length(ax, ay, accel_max)
    ux, uy = vel[0] / vn, vel[1] / vn
    along = ax * ux + ay * uy
    cx, cy = ax - along * ux, ay - along * uy
    if along * along <= cx * cx + cy * cy:
        return limit_length(ax, ay, accel_max)
    cx, cy, _ = limit_length(cx, cy, _CORNER_RATIO * accel_max)
    rest = math.sqrt(max(0.0, accel_max * accel_max - cx * cx - cy * cy))
    along = max(-rest, min(rest, along))
    return cx + along * ux, cy + along * uy, True


def shape_pos_vel_accel_xy(pos_want, vel_want, accel_want, pos, vel, accel, vel_max: float,
                           accel_max: float, jerk_max: float, dt_s: float, limit_total: bool
                           ) -> tuple[float, float]:
    """New acceleration target driving ``pos``/``vel`` toward ``pos_want``/``vel_want``."""
    kpv = 0.5 * jerk_max / accel_max
    vx, vy = sqrt_controller_xy(pos_want[0] - pos[0], pos_want[1] - pos[1], kpv,
                                0.5 * accel_max, dt_s)
    if vel_max > 0.0:
        vx, vy, _ = limit_length(vx, vy, vel_max)
    vx, vy = vx + vel_want[0], vy + vel_want[1]
    if limit_total and vel_max > 0.0:
        vx, vy, _ = limit_length(vx, vy, vel_max)
    return shape_vel_accel_xy((vx, vy), accel_want, vel, accel, accel_max, jerk_max, dt_s,
                              limit_total)


def advance_xy(pos, vel, accel, dt_s: float):
    """(pos, vel) after dt at constant ``accel``."""
    px = pos[0] + vel[0] * dt_s + 0.5 * accel[0] * dt_s * dt_s
    py = pos[1] + vel[1] * dt_s + 0.5 * accel[1] * dt_s * dt_s
    return (px, py), (vel[0] + accel[0] * dt_s, vel[1] + accel[1] * dt_s)
