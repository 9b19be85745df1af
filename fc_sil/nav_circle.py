"""Circling a point (MAV_CMD_NAV_LOITER_TURNS): a target moving round a circle, as AC_Circle.

ArduCopter 4.6's circle navigator, written from its behaviour:

* the target runs round the centre at an angle measured like a bearing (north 0, east
  +pi/2): positive angular velocity is clockwise seen from above. It starts from the
  vehicle's own bearing from the centre, at rest, and its angular velocity ramps at
  max(WPNAV_ACCEL / radius, 2 deg/s^2) to the largest rate that keeps the speed within
  WPNAV_SPEED and the centripetal acceleration within half of WPNAV_ACCEL
  (v = min(speed, sqrt(0.5 a r))), and within CIRCLE_RATE;
* ArduCopter hands only the target position to its position controller, whose input
  shaping trails it: its circle of 10 m at 20 deg/s measures 9.7 m. Here the target's own
  velocity and centripetal acceleration go with it (``update``), so the position controller
  flies the commanded radius instead of trailing the point round a smaller one;
* the vehicle faces the centre; the turns completed are |total angle| / 2 pi.

Units: metres, radians, seconds; positions NE about the estimator origin.
"""

from __future__ import annotations

import math

ANGULAR_ACCEL_MIN_RAD_S2 = math.radians(2.0)   # AC_Circle: never ramp slower than this


def wrap_pi(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class CircleNav:
    def __init__(self, center_ne, radius_m: float, rate_rad_s: float, speed_m_s: float,
                 accel_m_s2: float):
        self.center = (float(center_ne[0]), float(center_ne[1]))
        self.radius_m = max(0.0, float(radius_m))
        self.rate_rad_s = float(rate_rad_s)       # signed: + clockwise
        self.speed_m_s = speed_m_s
        self.accel_m_s2 = accel_m_s2
        self.angle_rad = 0.0
        self.angle_total_rad = 0.0
        self.angular_vel_rad_s = 0.0
        self._limits()

    def _limits(self) -> None:
        if self.radius_m <= 0.0:      # a turn on the spot (panorama)
            self.angular_vel_max = self.rate_rad_s
            self.angular_accel = max(abs(self.rate_rad_s), ANGULAR_ACCEL_MIN_RAD_S2)
            return
        v_max = min(self.speed_m_s, math.sqrt(0.5 * self.accel_m_s2 * self.radius_m))
        w_max = v_max / self.radius_m
        self.angular_vel_max = max(-w_max, min(w_max, self.rate_rad_s))
        self.angular_accel = max(self.accel_m_s2 / self.radius_m, ANGULAR_ACCEL_MIN_RAD_S2)

    def closest_edge(self, pos_ne, yaw_rad: float):
        """The point of the circle nearest pos (behind the vehicle if it is at the centre)."""
        dn, de = pos_ne[0] - self.center[0], pos_ne[1] - self.center[1]
        d = math.hypot(dn, de)
        if self.radius_m <= 0.0:
            return self.center
        if d < 1e-6:
            return (self.center[0] - self.radius_m * math.cos(yaw_rad),
                    self.center[1] - self.radius_m * math.sin(yaw_rad))
        return (self.center[0] + dn / d * self.radius_m, self.center[1] + de / d * self.radius_m)

    def start(self, pos_ne, yaw_rad: float) -> None:
        """Begin circling from where the vehicle is (its bearing from the centre), at rest."""
        self.angle_total_rad = 0.0
        self.angular_vel_rad_s = 0.0
        dn, de = pos_ne[0] - self.center[0], pos_ne[1] - self.center[1]
        if self.radius_m <= 0.0:
            self.angle_rad = yaw_rad
        elif math.hypot(dn, de) < 1e-6:
            self.angle_rad = wrap_pi(yaw_rad - math.pi)
        else:
            self.angle_rad = math.atan2(de, dn)

    def update(self, dt_s: float):
        """Advance the target; returns (position, velocity, acceleration), NE."""
        w, w_max, a = self.angular_vel_rad_s, self.angular_vel_max, self.angular_accel
        w = min(w + a * dt_s, w_max) if w < w_max else max(w - a * dt_s, w_max)
        self.angular_vel_rad_s = w
        self.angle_rad = wrap_pi(self.angle_rad + w * dt_s)
        self.angle_total_rad += w * dt_s
        c, s_ = math.cos(self.angle_rad), math.sin(self.angle_rad)
        r = self.radius_m
        vel = (-r * w * s_, r * w * c)
        acc = (-r * w * w * c, -r * w * w * s_)
        return self.target(), vel, acc

    def target(self):
        if self.radius_m <= 0.0:
            return self.center
        return (self.center[0] + self.radius_m * math.cos(self.angle_rad),
                self.center[1] + self.radius_m * math.sin(self.angle_rad))

    def yaw_rad(self, from_ne) -> float:
        """Heading that faces the centre from `from_ne` (the target's own angle when the
        radius is zero)."""
        if self.radius_m <= 0.0:
            return self.angle_rad
        return math.atan2(self.center[1] - from_ne[1], self.center[0] - from_ne[0])

    @property
    def turns_done(self) -> float:
        return abs(self.angle_total_rad) / (2.0 * math.pi)
