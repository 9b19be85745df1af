"""Waypoint navigation: a straight 3D leg flown along a jerk-limited S-curve (AC_WPNav's way).

The target point moves along the leg by an S-curve (nav_scurve.py) whose limits come from
WPNAV_SPEED, WPNAV_SPEED_UP/_DN, WPNAV_ACCEL, WPNAV_ACCEL_Z, WPNAV_JERK and a snap limit
derived as AC_WPNav does (half of min(pi J / (2 ATC_INPUT_TC), the lean's angular
acceleration limit x g), ATC_INPUT_TC at least 0.1 s), scaled to the
leg's direction as ArduCopter's kinematic limit does (the horizontal and vertical parts each
within their own limit). The position controller gets the point's position, velocity and
acceleration: all three feed forward, so the vehicle flies the curve instead of chasing a
point, and the curve ends at rest exactly on the destination.

When the vehicle falls behind horizontally (wind, a lean limit), the S-curve's clock slows:
the clock rate is 0.05 + (vehicle speed along the leg - PSC_POSXY_P x distance behind the
target) / target speed, horizontal parts only, clamped to 0..1 and low-passed with time
constant WPNAV_ACCEL / WPNAV_JERK. The target thus never runs away from the vehicle, and the vehicle is never asked
to catch up at more than the planned speed (the cause of our old 5.7 m overshoot on a 30 m
goto: the point ran ahead while the vehicle accelerated, and the catch-up speed then
exceeded what the planned deceleration could remove).

Reached: the curve has ended and the vehicle is within WPNAV_RADIUS horizontally and within
max(1 m, WPNAV_RADIUS) vertically.

Units: metres, m/s, m/s^2; positions NE about the estimator origin, altitude up above home.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .nav_scurve import SCurve


@dataclass
class WpSpeeds:
    speed_m_s: float = 10.0      # WPNAV_SPEED / 100
    up_m_s: float = 2.5          # WPNAV_SPEED_UP / 100
    dn_m_s: float = 1.5          # WPNAV_SPEED_DN / 100
    accel_m_s2: float = 2.5      # WPNAV_ACCEL / 100
    radius_m: float = 2.0        # WPNAV_RADIUS / 100
    jerk_m_s3: float = 1.0       # WPNAV_JERK (0 = WPNAV_ACCEL per second)
    accel_z_m_s2: float = 1.0    # WPNAV_ACCEL_Z / 100
    pos_p: float = 1.0           # PSC_POSXY_P, for the clock's catch-up term
    snap_m_s4: float = 0.0       # S-curve snap limit (AC_WPNav: from ATC_INPUT_TC); 0 = none

    @property
    def jerk(self) -> float:
        return self.jerk_m_s3 if self.jerk_m_s3 > 0.0 else self.accel_m_s2


def kinematic_limit(unit, xy: float, up: float, dn: float) -> float:
    """Largest magnitude along the 3D unit vector whose horizontal part is within xy and
    vertical part within up (climbing) or dn (descending)."""
    h = math.hypot(unit[0], unit[1])
    z = unit[2]
    lim = float("inf")
    if h > 1e-6:
        lim = xy / h
    if z > 1e-6:
        lim = min(lim, up / z)
    elif z < -1e-6:
        lim = min(lim, dn / -z)
    return lim if math.isfinite(lim) else 0.0


class WaypointNav:
    def __init__(self, speeds: WpSpeeds | None = None):
        self.sp = speeds or WpSpeeds()
        self.origin = (0.0, 0.0, 0.0)     # n, e, alt_up
        self.dest = (0.0, 0.0, 0.0)
        self.length_m = 0.0
        self.curve = SCurve(0.0, 1.0, 1.0, 1.0)
        self.t_s = 0.0                    # S-curve clock
        self.clock_rate = 1.0             # low-passed rate of the clock (the slow-down)
        self.s_m = 0.0                    # target point distance along the track
        self.track_speed_m_s = 0.0
        self.track_accel_m_s2 = 0.0
        self.active = False

    def set_destination(self, start_ne, start_alt_m: float, dest_ne, dest_alt_m: float,
                        start_speed_m_s: float = 0.0) -> None:
        """A new leg from start to dest; start_speed_m_s: the speed along it already flown."""
        self.origin = (float(start_ne[0]), float(start_ne[1]), float(start_alt_m))
        self.dest = (float(dest_ne[0]), float(dest_ne[1]), float(dest_alt_m))
        d = [b - a for a, b in zip(self.origin, self.dest)]
        self.length_m = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
        u = self._unit()
        sp = self.sp
        speed = kinematic_limit(u, sp.speed_m_s, sp.up_m_s, sp.dn_m_s)
        accel = kinematic_limit(u, sp.accel_m_s2, sp.accel_z_m_s2, sp.accel_z_m_s2)
        self.curve = SCurve(self.length_m, speed or 1.0, accel or 1.0, sp.jerk,
                            max(0.0, start_speed_m_s), sp.snap_m_s4)
        self.t_s = 0.0
        self.clock_rate = 1.0
        self.s_m = 0.0
        self.track_speed_m_s = max(0.0, start_speed_m_s)
        self.track_accel_m_s2 = 0.0
        self.active = True

    @property
    def bearing_rad(self) -> float | None:
        """Track bearing (north = 0, east = pi/2), None for a vertical track."""
        dn, de = self.dest[0] - self.origin[0], self.dest[1] - self.origin[1]
        if math.hypot(dn, de) < 0.5:
            return None
        return math.atan2(de, dn)

    def _unit(self) -> tuple[float, float, float]:
        if self.length_m < 1e-6:
            return 0.0, 0.0, 0.0
        return tuple((b - a) / self.length_m for a, b in zip(self.origin, self.dest))

    def _clock_target(self, pos_ne_m, vel_ne_m_s) -> float:
        """0.05 + (vehicle speed along - P x lag) / target speed, in 0..1 (AC_WPNav).

        Horizontal only: our vertical target goes to the C core's altitude controller, which
        has no climb-rate feed-forward and so lags a climbing target by design; a clock slowed
        by that lag would stall every climb (AC_WPNav measures the lag in 3D, against a
        vertical controller that is fed forward)."""
        u = self._unit()
        h = math.hypot(u[0], u[1])
        v = self.track_speed_m_s * self.clock_rate * h
        if h * self.length_m < 1.0 or v <= 1e-3:
            return 1.0          # (nearly) vertical: less than a metre to cover horizontally
        ux, uy = u[0] / h, u[1] / h
        tp = self.point(self.s_m)
        lag = (tp[0] - pos_ne_m[0]) * ux + (tp[1] - pos_ne_m[1]) * uy
        along = vel_ne_m_s[0] * ux + vel_ne_m_s[1] * uy
        return max(0.0, min(1.0, 0.05 + (along - self.sp.pos_p * lag) / v))

    def update(self, dt_s: float, pos_ne_m, alt_m: float, vel_ne_m_s=(0.0, 0.0),
               climb_m_s: float = 0.0):
        """Advance the target point; returns (target_ne, target_vel_ne, target_accel_ne,
        target_alt_m)."""
        want = self._clock_target(pos_ne_m, vel_ne_m_s)
        tc = self.sp.accel_m_s2 / self.sp.jerk
        self.clock_rate += (want - self.clock_rate) * min(1.0, dt_s / tc)
        self.t_s += self.clock_rate * dt_s
        s, v, a = self.curve.at(self.t_s)
        self.s_m, self.track_speed_m_s, self.track_accel_m_s2 = s, v, a
        # a slowed clock slows the point: speed x rate, acceleration x rate^2
        k = self.clock_rate
        u = self._unit()
        p = self.point(s)
        vel = (u[0] * v * k, u[1] * v * k)
        acc = (u[0] * a * k * k, u[1] * a * k * k)
        return (p[0], p[1]), vel, acc, p[2]

    def point(self, s_m: float) -> tuple[float, float, float]:
        if self.length_m < 1e-6:
            return self.dest
        f = s_m / self.length_m
        return tuple(a + f * (b - a) for a, b in zip(self.origin, self.dest))

    def distance_to_dest(self, pos_ne_m) -> float:
        return math.hypot(self.dest[0] - pos_ne_m[0], self.dest[1] - pos_ne_m[1])

    @property
    def curve_done(self) -> bool:
        return self.curve.finished(self.t_s)

    def reached(self, pos_ne_m, alt_m: float) -> bool:
        if not self.active or not self.curve_done:
            return False
        return (self.distance_to_dest(pos_ne_m) <= self.sp.radius_m
                and abs(self.dest[2] - alt_m) <= max(1.0, self.sp.radius_m))
