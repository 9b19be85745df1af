"""Spline legs (MAV_CMD_NAV_SPLINE_WAYPOINT): a cubic Hermite curve and a target point on it.

The geometry and speed rules of ArduCopter 4.6's SplineCurve (AP_Math), written from its
behaviour:

* a leg is the cubic Hermite curve p(t), t in [0, 1], from origin to destination whose
  end derivatives are the given origin and destination vectors (in metres per unit t). The
  mission chooses them (mission_nav.py): the previous leg's direction at the origin, and at
  the destination the vector to the next destination (straight next leg) or from this
  leg's origin to the next destination (spline next leg), so consecutive legs join with a
  continuous tangent. If the two vectors together are longer than four times the chord, both
  are scaled down so a short leg does not loop;
* the target point moves along the curve at a speed limited by WPNAV_SPEED / _SPEED_UP /
  _SPEED_DN in the direction of travel, by a cornering (normal) acceleration of half the
  acceleration limit (v^2 * curvature <= 0.5 a), changes speed at most half the acceleration
  limit per second, and brakes so it arrives at the speed the next leg can take (zero when
  the mission stops here): v <= sqrt(2 a_t (d + v_end^2 / 2 a_t)), d the straight distance
  to the destination;
* as ArduCopter's waypoint navigator, the target's progress is slowed while the vehicle lags
  behind it (a time scale in [0, 1], filtered with WPNAV_ACCEL / WPNAV_JERK), so a gust never
  leaves the vehicle chasing a point far ahead;
* reached: the target is at the destination and, unless the leg ends moving (the next leg
  continues from here), the vehicle is within WPNAV_RADIUS of it.

Units: metres, seconds; points and vectors are (north, east, up) about the estimator origin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

SPLINE_FACTOR = 4.0              # end vectors longer than this x chord are scaled down
TANGENTIAL_ACCEL_SCALER = 0.5    # share of the acceleration limit used along the track
LATERAL_ACCEL_SCALER = 0.5       # share used across it (cornering)


@dataclass
class SplineLimits:
    speed_xy_m_s: float = 10.0     # WPNAV_SPEED (or DO_CHANGE_SPEED)
    speed_up_m_s: float = 2.5      # WPNAV_SPEED_UP
    speed_dn_m_s: float = 1.5      # WPNAV_SPEED_DN
    accel_xy_m_s2: float = 2.5     # WPNAV_ACCEL
    accel_z_m_s2: float = 1.0      # WPNAV_ACCEL_Z
    jerk_m_s3: float = 1.0         # WPNAV_JERK: sets the time constant of the lag slow-down
    radius_m: float = 2.0          # WPNAV_RADIUS
    pos_p: float = 1.0             # PSC_POSXY_P: how much lag the position loop expects


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _mul(a, k: float):
    return (a[0] * k, a[1] * k, a[2] * k)


def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _norm(a) -> float:
    return math.sqrt(_dot(a, a))


def kinematic_limit(direction, max_xy: float, max_up: float, max_dn: float) -> float:
    """Largest magnitude along `direction` whose horizontal part stays within max_xy and
    whose vertical part within max_up (up) or max_dn (down); 0 for a zero direction."""
    n = _norm(direction)
    if n <= 0.0:
        return 0.0
    xy = math.hypot(direction[0], direction[1]) / n
    z = direction[2] / n
    lim = math.inf
    if xy > 1e-9:
        lim = abs(max_xy) / xy
    if z > 1e-9:
        lim = min(lim, abs(max_up) / z)
    elif z < -1e-9:
        lim = min(lim, abs(max_dn) / -z)
    return lim if math.isfinite(lim) else 0.0


class SplineLeg:
    """One Hermite leg: geometry, and the speed a target may have at a point of it."""

    def __init__(self, origin, dest, origin_vec, dest_vec, limits: SplineLimits):
        self.origin = tuple(float(x) for x in origin)
        self.dest = tuple(float(x) for x in dest)
        self.origin_vec = tuple(float(x) for x in origin_vec)
        self.dest_vec = tuple(float(x) for x in dest_vec)
        self.lim = limits
        chord = _norm(_sub(self.dest, self.origin))
        self.zero_length = chord <= 1e-6
        v0, v1 = self.origin_vec, self.dest_vec
        vel_len = _norm(v0) + _norm(v1)
        if vel_len > chord * SPLINE_FACTOR and vel_len > 0.0:
            k = chord * SPLINE_FACTOR / vel_len
            v0, v1 = _mul(v0, k), _mul(v1, k)
        p0, p1 = self.origin, self.dest
        # p(t) = c0 + c1 t + c2 t^2 + c3 t^3 with p(0)=p0, p(1)=p1, p'(0)=v0, p'(1)=v1
        self.c = (p0, v0,
                  _sub(_sub(_mul(_sub(p1, p0), 3.0), _mul(v0, 2.0)), v1),
                  _add(_add(_mul(_sub(p0, p1), 2.0), v0), v1))
        # the speed the leg can end with (its curvature and speed limits there; 0 when it
        # ends at rest), then the speed it can start with and still arrive at that
        self.dest_speed_max = math.inf
        if self.zero_length or _norm(self.dest_vec) <= 0.0:
            self.dest_speed_max = 0.0
        else:
            self.dest_speed_max = self.limits_at(1.0, 0.0)[2]
        self.origin_speed_max = 0.0 if self.zero_length else self.limits_at(0.0, 0.0)[2]

    def eval(self, t: float):
        """(position, dp/dt, d2p/dt2, d3p/dt3) at curve parameter t."""
        c0, c1, c2, c3 = self.c
        pos = _add(_add(c0, _mul(c1, t)), _add(_mul(c2, t * t), _mul(c3, t * t * t)))
        vel = _add(c1, _add(_mul(c2, 2.0 * t), _mul(c3, 3.0 * t * t)))
        acc = _add(_mul(c2, 2.0), _mul(c3, 6.0 * t))
        return pos, vel, acc, _mul(c3, 6.0)

    def limits_at(self, t: float, step_m: float):
        """At parameter t: (dt for a move of step_m, unit tangent, speed max, accel max,
        position)."""
        lim = self.lim
        pos, vel, acc, jerk = self.eval(t)
        vlen = _norm(vel)
        if vlen > 1e-9:
            unit = _mul(vel, 1.0 / vlen)
            dt = step_m / vlen
        elif _norm(acc) > 1e-9:          # a cusp: the direction comes from the acceleration
            unit = _mul(acc, 1.0 / _norm(acc))
            dt = math.sqrt(2.0 * step_m / _norm(acc))
        else:
            unit = _mul(jerk, 1.0 / max(_norm(jerk), 1e-9))
            dt = (6.0 * step_m / max(_norm(jerk), 1e-9)) ** (1.0 / 3.0)
        acc_normal = _sub(acc, _mul(unit, _dot(acc, unit)))
        an = _norm(acc_normal)
        v_max = kinematic_limit(unit, lim.speed_xy_m_s, lim.speed_up_m_s, lim.speed_dn_m_s)
        a_norm_max = LATERAL_ACCEL_SCALER * kinematic_limit(
            acc_normal, lim.accel_xy_m_s2, lim.accel_z_m_s2, lim.accel_z_m_s2)
        if a_norm_max > 0.0 and an > 0.0 and vlen > 0.0 and v_max > 0.0 \
                and an / a_norm_max > (vlen / v_max) ** 2:
            # curvature = an / vlen^2; cornering: v^2 * curvature <= a_norm_max
            v_max = vlen / math.sqrt(an / a_norm_max)
        a_max = TANGENTIAL_ACCEL_SCALER * kinematic_limit(
            unit, lim.accel_xy_m_s2, lim.accel_z_m_s2, lim.accel_z_m_s2)
        if a_max > 0.0 and math.isfinite(self.dest_speed_max):
            d = _norm(_sub(self.dest, pos))
            v_max = min(v_max, math.sqrt(2.0 * a_max * d + self.dest_speed_max ** 2))
        return dt, unit, v_max, a_max, pos


class SplineNav:
    """Drives a target point along one SplineLeg; update/reached as nav_wp.WaypointNav."""

    def __init__(self, limits: SplineLimits | None = None):
        self.lim = limits or SplineLimits()
        self.leg: SplineLeg | None = None
        self.t = 1.0
        self.speed_m_s = 0.0          # target point speed along the curve
        self.time_scale = 1.0         # < 1 while the vehicle lags the target
        self.vel = (0.0, 0.0, 0.0)    # target velocity (NEU)
        self.active = False

    def set_leg(self, origin, dest, origin_vec, dest_vec, start_speed_m_s: float = 0.0) -> None:
        self.leg = SplineLeg(origin, dest, origin_vec, dest_vec, self.lim)
        self.t = 1.0 if self.leg.zero_length else 0.0
        self.speed_m_s = max(0.0, float(start_speed_m_s))
        self.time_scale = 1.0
        self.vel = (0.0, 0.0, 0.0)
        self.active = True

    def set_destination_speed_max(self, speed_m_s: float) -> None:
        """The next leg cannot start faster than this: arrive no faster."""
        if self.leg is not None:
            self.leg.dest_speed_max = min(self.leg.dest_speed_max, max(0.0, speed_m_s))

    @property
    def dest(self):
        return self.leg.dest if self.leg else (0.0, 0.0, 0.0)

    @property
    def ends_moving(self) -> bool:
        """True when the next leg continues from here without a stop (a 'fast' waypoint)."""
        return self.leg is not None and _norm(self.leg.dest_vec) > 0.0

    @property
    def bearing_rad(self) -> float | None:
        """Direction of travel of the target (north = 0), None while it is not moving."""
        if math.hypot(self.vel[0], self.vel[1]) < 0.1:
            return None
        return math.atan2(self.vel[1], self.vel[0])

    def _lag_scale(self, dt_s: float, pos_neu, vel_neu) -> None:
        """ArduCopter's track time scale: slow the target while the vehicle falls behind."""
        vt = _norm(self.vel)
        target = 1.0
        if vt > 1e-6 and pos_neu is not None and vel_neu is not None:
            u = _mul(self.vel, 1.0 / vt)
            tp = self.leg.eval(self.t)[0]
            err = _dot(_sub(tp, pos_neu), u)
            target = min(1.0, max(0.0, 0.05 + (_dot(vel_neu, u) - self.lim.pos_p * err) / vt))
        tc = self.lim.accel_xy_m_s2 / self.lim.jerk_m_s3 if self.lim.jerk_m_s3 > 0 else 1.0
        self.time_scale += (target - self.time_scale) * min(1.0, dt_s / max(tc, 1e-3))

    def update(self, dt_s: float, pos_ne_m, alt_m: float, vel_neu=None):
        """Advance the target; returns (target_ne, target_vel_ne, target_alt_m)."""
        leg = self.leg
        if leg is None or leg.zero_length:
            d = self.dest
            self.vel = (0.0, 0.0, 0.0)
            return (d[0], d[1]), (0.0, 0.0), d[2]
        here = (float(pos_ne_m[0]), float(pos_ne_m[1]), float(alt_m))
        self._lag_scale(dt_s, here, vel_neu)
        dt = dt_s * self.time_scale
        step_dt, unit, v_max, a_max, pos = leg.limits_at(self.t, self.speed_m_s * dt)
        self.speed_m_s = min(max(v_max, self.speed_m_s - a_max * dt), self.speed_m_s + a_max * dt)
        self.speed_m_s = max(0.0, self.speed_m_s)
        self.vel = _mul(unit, self.speed_m_s)   # the lag scale slows progress, not the feed-forward
        self.t = min(1.0, self.t + step_dt)
        return (pos[0], pos[1]), (self.vel[0], self.vel[1]), pos[2]

    def target_done(self) -> bool:
        return self.leg is not None and self.t >= 1.0

    def reached(self, pos_ne_m, alt_m: float) -> bool:
        if not self.active or not self.target_done():
            return False
        if self.ends_moving:
            return True
        d = _sub((float(pos_ne_m[0]), float(pos_ne_m[1]), float(alt_m)), self.dest)
        return _norm(d) <= self.lim.radius_m
