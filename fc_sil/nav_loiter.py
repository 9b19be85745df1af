"""LoiterNav: the pilot's sticks -> a shaped velocity/position target (ArduCopter's AC_Loiter).

The sticks ask for a lean angle (full stick = LOIT_ANG_MAX, or two thirds of the position
controller's lean limit when 0), i.e. an acceleration. The desired velocity integrates that
acceleration less a drag that grows with speed (drag = stick-limit acceleration x speed /
LOIT_SPEED, so a held full stick settles at LOIT_SPEED). With the sticks centred for
LOIT_BRK_DELAY the vehicle brakes: a braking deceleration, up to LOIT_BRK_ACCEL, reached
at LOIT_BRK_JERK, from a sqrt controller on the speed (gain PSC_VELXY_P / 2). The position
target moves with the desired velocity, so when the velocity reaches zero the vehicle holds
where it stopped, and the position controller (corrections limited to 2 m/s and
LOIT_ACC_MAX, as AC_Loiter sets them) holds it there.

ArduCopter predicts the lean the attitude controller will reach from the sticks through its
input-shaping model; here the acceleration the sticks ask for reaches the prediction through
a first-order lag of ATC_INPUT_TC (the same time constant, without the rate limit).

NE metres, m/s, m/s^2; ``update`` returns the (pos, vel, accel) targets for the controller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .nav_kinematics import limit_length, sqrt_controller
from .nav_pos import lean_to_accel

# AC_Loiter's fixed correction limits (LOITER_VEL_CORRECTION_MAX, LOITER_POS_CORRECTION_MAX)
CORRECTION_SPEED_M_S = 2.0
CORRECTION_POS_M = 2.0
SPEED_MIN_M_S = 0.2         # LOITER_SPEED_MIN


@dataclass
class LoiterConfig:
    speed_m_s: float = 12.5         # LOIT_SPEED / 100
    accel_max_m_s2: float = 5.0     # LOIT_ACC_MAX / 100
    brake_accel_m_s2: float = 2.5   # LOIT_BRK_ACCEL / 100
    brake_jerk_m_s3: float = 5.0    # LOIT_BRK_JERK / 100
    brake_delay_s: float = 1.0      # LOIT_BRK_DELAY
    angle_max_rad: float = math.radians(20.0)   # LOIT_ANG_MAX, or 2/3 of the lean limit
    vel_p: float = 2.0              # PSC_VELXY_P (braking gain = half of it)
    input_tc_s: float = 0.15        # ATC_INPUT_TC (the predicted lean's lag)


class LoiterNav:
    def __init__(self, cfg: LoiterConfig | None = None):
        self.cfg = cfg or LoiterConfig()
        self.reset((0.0, 0.0), (0.0, 0.0))

    def reset(self, vel_ne_m_s, accel_ne_m_s2) -> None:
        self.desired_vel = (float(vel_ne_m_s[0]), float(vel_ne_m_s[1]))
        self.predicted_accel = (float(accel_ne_m_s2[0]), float(accel_ne_m_s2[1]))
        self.brake_accel = 0.0
        self.sticks_idle_s = 0.0

    def update(self, dt_s: float, pos_target_ne, roll_in: float, pitch_in: float,
               yaw_rad: float):
        """One step from the sticks (-1..1); returns (pos, vel, accel) targets."""
        c = self.cfg
        ang = c.angle_max_rad
        want = lean_to_accel(roll_in * ang, pitch_in * ang, yaw_rad)
        k = min(1.0, dt_s / max(c.input_tc_s, dt_s))
        self.predicted_accel = (self.predicted_accel[0] + (want[0] - self.predicted_accel[0]) * k,
                                self.predicted_accel[1] + (want[1] - self.predicted_accel[1]) * k)
        sticks = roll_in != 0.0 or pitch_in != 0.0
        self.sticks_idle_s = 0.0 if sticks else self.sticks_idle_s + dt_s
        limit = max(c.speed_m_s, SPEED_MIN_M_S)
        pilot_accel_max = 9.80665 * math.tan(ang)
        vx = self.desired_vel[0] + self.predicted_accel[0] * dt_s
        vy = self.desired_vel[1] + self.predicted_accel[1] * dt_s
        accel = want
        speed = math.hypot(vx, vy)
        if speed > 0.0:
            ux, uy = vx / speed, vy / speed
            drag = pilot_accel_max * speed / limit
            brake_want = 0.0
            if not sticks and self.sticks_idle_s > c.brake_delay_s:
                brake_want = min(c.brake_accel_m_s2, max(0.0, sqrt_controller(
                    speed, c.vel_p * 0.5, c.brake_jerk_m_s3, dt_s)))
            step = c.brake_jerk_m_s3 * dt_s
            self.brake_accel += max(-step, min(step, brake_want - self.brake_accel))
            speed = max(0.0, speed - (drag + self.brake_accel) * dt_s)
            vx, vy = ux * speed, uy * speed
            accel = (want[0] - ux * self.brake_accel, want[1] - uy * self.brake_accel)
        vx, vy, _ = limit_length(vx, vy, limit)
        self.desired_vel = (vx, vy)
        pos = (pos_target_ne[0] + vx * dt_s, pos_target_ne[1] + vy * dt_s)
        return pos, (vx, vy), accel
