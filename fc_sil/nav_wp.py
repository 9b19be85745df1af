"""Waypoint navigation: a straight 3D track from the present position to a destination.

A target point runs along the track (as ArduCopter's wpnav does) and the position
controller follows it with the target point's velocity as feed-forward:

* along-track speed: at most WPNAV_SPEED horizontally and WPNAV_SPEED_UP / _DN vertically
  (the 3D speed is scaled so neither component exceeds its limit), reached and left at
  WPNAV_ACCEL, and never more than sqrt(2 a d) at distance d from the end, so the target
  point stops exactly at the destination;
* leash: the target point waits while the vehicle is more than a braking distance (+1 m)
  behind it, so a gust or a slow climb never leaves the vehicle chasing a far-away point;
* reached: once the target point is at the destination and the vehicle is within
  WPNAV_RADIUS horizontally and within max(1 m, WPNAV_RADIUS) vertically.

Units: metres and m/s, positions NE about the estimator origin, altitude up above home.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class WpSpeeds:
    speed_m_s: float = 10.0      # WPNAV_SPEED / 100
    up_m_s: float = 2.5          # WPNAV_SPEED_UP / 100
    dn_m_s: float = 1.5          # WPNAV_SPEED_DN / 100
    accel_m_s2: float = 2.5      # WPNAV_ACCEL / 100
    radius_m: float = 2.0        # WPNAV_RADIUS / 100


class WaypointNav:
    def __init__(self, speeds: WpSpeeds | None = None):
        self.sp = speeds or WpSpeeds()
        self.origin = (0.0, 0.0, 0.0)     # n, e, alt_up
        self.dest = (0.0, 0.0, 0.0)
        self.length_m = 0.0
        self.s_m = 0.0                    # target point distance along the track
        self.track_speed_m_s = 0.0
        self.active = False

    def set_destination(self, start_ne, start_alt_m: float, dest_ne, dest_alt_m: float,
                        start_speed_m_s: float = 0.0) -> None:
        self.origin = (float(start_ne[0]), float(start_ne[1]), float(start_alt_m))
        self.dest = (float(dest_ne[0]), float(dest_ne[1]), float(dest_alt_m))
        d = [b - a for a, b in zip(self.origin, self.dest)]
        self.length_m = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
        self.s_m = 0.0
        self.track_speed_m_s = max(0.0, start_speed_m_s)
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

    def _speed_limit(self) -> float:
        u = self._unit()
        h = math.hypot(u[0], u[1])
        lim = float("inf")
        if h > 1e-6:
            lim = min(lim, self.sp.speed_m_s / h)
        if u[2] > 1e-6:
            lim = min(lim, self.sp.up_m_s / u[2])
        elif u[2] < -1e-6:
            lim = min(lim, self.sp.dn_m_s / -u[2])
        return lim if math.isfinite(lim) else 0.0

    def update(self, dt_s: float, pos_ne_m, alt_m: float):
        """Advance the target point; returns (target_ne, target_vel_ne, target_alt_m)."""
        u = self._unit()
        remaining = max(0.0, self.length_m - self.s_m)
        v_goal = min(self._speed_limit(), math.sqrt(2.0 * self.sp.accel_m_s2 * remaining))
        # leash: how far the vehicle is behind the target point (3D)
        tp = self.point(self.s_m)
        lag = math.sqrt((tp[0] - pos_ne_m[0]) ** 2 + (tp[1] - pos_ne_m[1]) ** 2
                        + (tp[2] - alt_m) ** 2)
        leash = self.track_speed_m_s ** 2 / (2.0 * self.sp.accel_m_s2) + 1.0
        if lag > leash + 1.0:
            v_goal = min(v_goal, self.track_speed_m_s)      # hold speed, do not run away
            if lag > 2.0 * leash + 2.0:
                v_goal = 0.0
        dv = max(-self.sp.accel_m_s2 * dt_s, min(self.sp.accel_m_s2 * dt_s,
                                                 v_goal - self.track_speed_m_s))
        self.track_speed_m_s = max(0.0, self.track_speed_m_s + dv)
        self.s_m = min(self.length_m, self.s_m + self.track_speed_m_s * dt_s)
        if self.s_m >= self.length_m:
            self.track_speed_m_s = 0.0
        p = self.point(self.s_m)
        v = (u[0] * self.track_speed_m_s, u[1] * self.track_speed_m_s)
        return (p[0], p[1]), v, p[2]

    def point(self, s_m: float) -> tuple[float, float, float]:
        if self.length_m < 1e-6:
            return self.dest
        f = s_m / self.length_m
        return tuple(a + f * (b - a) for a, b in zip(self.origin, self.dest))

    def distance_to_dest(self, pos_ne_m) -> float:
        return math.hypot(self.dest[0] - pos_ne_m[0], self.dest[1] - pos_ne_m[1])

    def reached(self, pos_ne_m, alt_m: float) -> bool:
        if not self.active or self.s_m < self.length_m:
            return False
        return (self.distance_to_dest(pos_ne_m) <= self.sp.radius_m
                and abs(self.dest[2] - alt_m) <= max(1.0, self.sp.radius_m))
