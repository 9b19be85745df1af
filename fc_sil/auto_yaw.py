"""Where an autonomous mode points the nose, and how that heading reaches the C core.

``AutoYaw`` follows ArduCopter 4.6's Mode::AutoYaw (ArduCopter/autoyaw.cpp): a yaw *mode*
chosen by the last command, and each step a heading target plus a rate feed-forward:

  HOLD             keep the present heading target (rate 0)
  LOOK_AT_NEXT_WP  face the desired direction of travel while it is over 5 % of the speed
                   limit (WP_YAW_BEHAVIOR 1 and 2; ArduCopter takes it from AC_PosControl)
  LOOK_AHEAD       face the actual direction of travel above 1 m/s (WP_YAW_BEHAVIOR 3)
  FIXED            CONDITION_YAW and relative (BODY frame) yaw: the target walks to the
                   angle at ATC_SLEW_YAW, or at the command's slower rate
  ANGLE_RATE       absolute yaw (and yaw rate) of SET_POSITION_TARGET: the target jumps to the
                   angle, then moves at the rate
  RATE             a yaw rate alone
  PILOT_RATE       the pilot's yaw stick (unless GUID_OPTIONS says to ignore it)

``HeadingControl`` is the attitude controller's part (AC_AttitudeControl's
input_thrust_vector_heading): the target is shaped by a sqrt controller with gain
1/ATC_INPUT_TC and ATC_ACCEL_Y_MAX, its rate limited to ATC_SLEW_YAW (and ATC_RATE_Y_MAX), and
ArduCopter closes ATC_ANG_YAW_P on the shaped heading. Our core holds a heading only when its
ATC_ANG_YAW_P > 0; by default it is 0 (the paper's yaw rate damping), and a heading target
given to it is then ignored: the navigation modes would never turn. So with the core's heading
loop off, this closes the loop here, at the outer-loop rate, with ArduCopter's default angle
gain, and gives the core a yaw rate; with it on, the shaped heading goes to the core as an
angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

# ArduCopter's ATC_ANG_YAW_P default [1/s]: the heading loop ArduCopter closes in every
# autonomous mode. Used here only while the core's own ATC_ANG_YAW_P is 0 (see module text).
ARDUCOPTER_ANG_YAW_P = 4.5
# AC_PosControl turns the heading to the desired velocity only above 5 % of the speed limit.
LOOK_AT_WP_MIN_SPEED_FRACTION = 0.05
# autoyaw.cpp YAW_LOOK_AHEAD_MIN_SPEED: 100 cm/s.
LOOK_AHEAD_MIN_SPEED_M_S = 1.0


def wrap_pi(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class YawRequest:
    """The yaw part of a GUIDED target (ArduCopter's use_yaw, yaw, use_yaw_rate, yaw_rate,
    relative_angle)."""
    use_yaw: bool = False
    yaw_rad: float = 0.0
    use_rate: bool = False
    rate_rad_s: float = 0.0
    relative: bool = False


NO_YAW = YawRequest()


class YawMode(Enum):
    HOLD = "hold"
    LOOK_AT_NEXT_WP = "look_at_next_wp"
    LOOK_AHEAD = "look_ahead"
    FIXED = "fixed"
    ANGLE_RATE = "angle_rate"
    RATE = "rate"
    PILOT_RATE = "pilot_rate"


# Modes that give only a rate (ArduCopter HeadingMode::Rate_Only); the others give an angle.
RATE_ONLY = frozenset({YawMode.HOLD, YawMode.RATE, YawMode.PILOT_RATE})


@dataclass(frozen=True)
class YawConfig:
    """The parameters the heading path reads, in SI units."""
    slew_max_rad_s: float = math.radians(60.0)       # min(ATC_SLEW_YAW, ATC_RATE_Y_MAX)
    rate_max_rad_s: float = 0.0                      # ATC_RATE_Y_MAX, 0 = none
    accel_max_rad_s2: float = math.radians(270.0)    # ATC_ACCEL_Y_MAX, 0 = none
    input_tc_s: float = 0.15                         # ATC_INPUT_TC
    core_ang_p: float = 0.0                          # the core's ATC_ANG_YAW_P
    wp_yaw_behavior: int = 2                         # WP_YAW_BEHAVIOR

    @classmethod
    def from_store(cls, get) -> "YawConfig":
        slew = math.radians(get("ATC_SLEW_YAW") * 0.01)
        rate_max = math.radians(get("ATC_RATE_Y_MAX"))
        if rate_max > 0.0:
            slew = min(slew, rate_max)
        return cls(slew_max_rad_s=slew, rate_max_rad_s=rate_max,
                   accel_max_rad_s2=math.radians(get("ATC_ACCEL_Y_MAX") * 0.01),
                   input_tc_s=float(get("ATC_INPUT_TC")), core_ang_p=float(get("ATC_ANG_YAW_P")),
                   wp_yaw_behavior=int(get("WP_YAW_BEHAVIOR")))


class AutoYaw:
    """ArduCopter's AutoYaw for one mode instance. ``target(...)`` once per step."""

    def __init__(self, yaw_rad: float):
        self.mode = YawMode.HOLD
        self.yaw_rad = yaw_rad            # heading target [rad]
        self.rate_rad_s = 0.0             # rate of RATE / ANGLE_RATE / PILOT_RATE [rad/s]
        self.fixed_offset_rad = 0.0       # FIXED: what is left to turn [rad]
        self.fixed_slew_rad_s = 0.0       # FIXED: how fast [rad/s]
        self.look_ahead_rad = yaw_rad

    def set_mode(self, mode: YawMode, yaw_now_rad: float) -> None:
        if mode == self.mode:
            return
        self.mode = mode
        if mode == YawMode.LOOK_AHEAD:
            self.look_ahead_rad = yaw_now_rad
        elif mode == YawMode.RATE:
            self.rate_rad_s = 0.0

    def set_default(self, behavior: int, yaw_now_rad: float, rtl: bool = False) -> None:
        """WP_YAW_BEHAVIOR: 0 hold, 1 look at the next waypoint, 2 the same except in RTL,
        3 look ahead (along the velocity)."""
        if behavior == 0 or (behavior == 2 and rtl):
            mode = YawMode.HOLD
        elif behavior == 3:
            mode = YawMode.LOOK_AHEAD
        else:
            mode = YawMode.LOOK_AT_NEXT_WP
        self.set_mode(mode, yaw_now_rad)

    def set_fixed(self, angle_rad: float, turn_rate_rad_s: float, direction: int,
                  relative: bool, slew_max_rad_s: float, yaw_now_rad: float) -> None:
        """CONDITION_YAW semantics: direction < 0 turns counter-clockwise, > 0 clockwise,
        0 the short way (relative angles with direction 0 turn clockwise, as ArduCopter)."""
        if relative:
            if self.mode == YawMode.HOLD:
                self.yaw_rad = yaw_now_rad
            self.fixed_offset_rad = angle_rad * (1.0 if direction >= 0 else -1.0)
        else:
            off = wrap_pi(angle_rad - self.yaw_rad)
            if direction < 0 and off > 0.0:
                off -= 2.0 * math.pi
            elif direction > 0 and off < 0.0:
                off += 2.0 * math.pi
            self.fixed_offset_rad = off
        self.fixed_slew_rad_s = (min(slew_max_rad_s, turn_rate_rad_s) if turn_rate_rad_s > 0.0
                                 else slew_max_rad_s)
        self.set_mode(YawMode.FIXED, yaw_now_rad)

    def set_angle_rate(self, angle_rad: float, rate_rad_s: float, yaw_now_rad: float) -> None:
        self.yaw_rad = angle_rad
        self.rate_rad_s = rate_rad_s
        self.set_mode(YawMode.ANGLE_RATE, yaw_now_rad)

    def set_rate(self, rate_rad_s: float, yaw_now_rad: float) -> None:
        self.set_mode(YawMode.RATE, yaw_now_rad)
        self.rate_rad_s = rate_rad_s

    def target(self, dt_s: float, shaped_rad: float, desired_vel_ne, speed_max_m_s: float,
               vel_ne) -> tuple[float, float, bool]:
        """(heading target [rad], rate feed-forward [rad/s], True if the angle counts).

        shaped_rad: the attitude controller's present heading target (HOLD and the rate modes
        keep it); desired_vel_ne: where the position controller wants to go [m/s];
        vel_ne: the estimated velocity [m/s]."""
        m = self.mode
        if m in RATE_ONLY:
            self.yaw_rad = shaped_rad
            return shaped_rad, (0.0 if m == YawMode.HOLD else self.rate_rad_s), False
        if m == YawMode.FIXED:
            step = max(-dt_s * self.fixed_slew_rad_s,
                       min(dt_s * self.fixed_slew_rad_s, self.fixed_offset_rad))
            self.fixed_offset_rad -= step
            self.yaw_rad = wrap_pi(self.yaw_rad + step)
            return self.yaw_rad, 0.0, True
        if m == YawMode.ANGLE_RATE:
            self.yaw_rad = wrap_pi(self.yaw_rad + self.rate_rad_s * dt_s)
            return self.yaw_rad, self.rate_rad_s, True
        if m == YawMode.LOOK_AHEAD:
            if math.hypot(*vel_ne) > LOOK_AHEAD_MIN_SPEED_M_S:
                self.look_ahead_rad = math.atan2(vel_ne[1], vel_ne[0])
            self.yaw_rad = self.look_ahead_rad
            return self.yaw_rad, 0.0, True
        # LOOK_AT_NEXT_WP
        if math.hypot(*desired_vel_ne) > LOOK_AT_WP_MIN_SPEED_FRACTION * speed_max_m_s:
            self.yaw_rad = math.atan2(desired_vel_ne[1], desired_vel_ne[0])
        else:
            self.yaw_rad = shaped_rad
        return self.yaw_rad, 0.0, True

    def reached_fixed(self, yaw_now_rad: float) -> bool:
        """FIXED: done slewing and within 2 deg (ArduCopter's reached_fixed_yaw_target)."""
        if self.mode != YawMode.FIXED:
            return True
        return self.fixed_offset_rad == 0.0 and \
            abs(wrap_pi(yaw_now_rad - self.yaw_rad)) <= math.radians(2.0)


def sqrt_controller(error: float, p: float, accel_max: float, dt_s: float) -> float:
    """ArduPilot's sqrt controller (AP_Math/control.cpp): linear near zero, the braking curve
    sqrt(2 a |e|) beyond, and never more than the error in one step."""
    if accel_max <= 0.0:
        out = error * p
    elif p <= 0.0:
        out = math.copysign(math.sqrt(2.0 * accel_max * abs(error)), error)
    else:
        linear = accel_max / (p * p)
        if abs(error) > linear:
            out = math.copysign(math.sqrt(2.0 * accel_max * (abs(error) - linear / 2.0)), error)
        else:
            out = error * p
    if dt_s > 0.0 and abs(out) > abs(error) / dt_s:
        out = error / dt_s
    return out


class HeadingControl:
    """The shaped heading target (ArduCopter's attitude target yaw) and what the core is given.

    ``update`` returns (yaw_target_rad, yaw_rate_cmd): the vehicle's v.yaw_target_rad and
    v.yaw_rate_cmd (None = the core holds the angle)."""

    def __init__(self, yaw_rad: float):
        self.reset(yaw_rad)

    def reset(self, yaw_rad: float) -> None:
        self.shaped_rad = yaw_rad
        self.rate_rad_s = 0.0

    def update(self, dt_s: float, cfg: YawConfig, yaw_now_rad: float, target_rad: float,
               rate_ff_rad_s: float, angle: bool, rate_max_rad_s: float | None = None
               ) -> tuple[float, float | None]:
        """rate_max_rad_s: the rate limit (default cfg.slew_max_rad_s, ATC_SLEW_YAW; attitude
        targets use ATC_RATE_Y_MAX, 0 = none)."""
        lim = cfg.slew_max_rad_s if rate_max_rad_s is None else rate_max_rad_s
        ff = max(-lim, min(lim, rate_ff_rad_s)) if lim > 0.0 else rate_ff_rad_s
        if angle:
            err = wrap_pi(target_rad - self.shaped_rad)
            want = ff + sqrt_controller(err, 1.0 / max(cfg.input_tc_s, 0.01),
                                        cfg.accel_max_rad_s2, dt_s)
        else:
            want = ff
        if lim > 0.0:
            want = max(-lim, min(lim, want))
        if cfg.accel_max_rad_s2 > 0.0:
            dv = cfg.accel_max_rad_s2 * dt_s
            want = max(self.rate_rad_s - dv, min(self.rate_rad_s + dv, want))
        self.rate_rad_s = want
        self.shaped_rad = wrap_pi(self.shaped_rad + want * dt_s)
        if cfg.core_ang_p > 0.0:
            return self.shaped_rad, None
        corr = sqrt_controller(wrap_pi(self.shaped_rad - yaw_now_rad), ARDUCOPTER_ANG_YAW_P,
                               cfg.accel_max_rad_s2, dt_s)
        return self.shaped_rad, self.rate_rad_s + corr
