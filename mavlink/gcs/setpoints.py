"""GUIDED/offboard inputs decoded into the vehicle's setpoint types, and their type_mask read
the way ArduCopter 4.6 reads it (ArduCopter/GCS_MAVLink_Copter.cpp).

SET_POSITION_TARGET_LOCAL_NED, SET_POSITION_TARGET_GLOBAL_INT and SET_ATTITUDE_TARGET reach the
vehicle with their frame and type_mask untouched, whatever the frame: ArduCopter answers an
unusable one by stopping (GUIDED's init: velocity 0, hold), so the vehicle must see it.

``position_mask_use``: a group (position, velocity, acceleration) counts as ignored when ANY
of its three ignore bits is set. Accepted: position; velocity; acceleration; position +
velocity (+ acceleration); velocity + acceleration. Refused, and the vehicle stops: position +
acceleration without velocity, and nothing at all (a yaw or yaw rate alone). FORCE_SET with
the acceleration used is dropped without stopping (checked against the real ArduCopter 4.6.0:
it flies on until GUID_TIMEOUT; later ArduPilot stops on it). No STATUSTEXT, no answer: the
message has none.
``attitude_mask_use``: refused (stop) when the thrust is ignored, when some but not all body
rates are ignored, or when the quaternion used is not unit length (+-1e-3 on its square).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import AttitudeTarget, PositionTarget

LOCAL_FRAMES = frozenset({mav.MAV_FRAME_LOCAL_NED, mav.MAV_FRAME_LOCAL_OFFSET_NED,
                          mav.MAV_FRAME_BODY_NED, mav.MAV_FRAME_BODY_OFFSET_NED})
GLOBAL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                           mav.MAV_FRAME_GLOBAL_INT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                           mav.MAV_FRAME_GLOBAL_TERRAIN_ALT, mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})


def position_target_local(msg) -> PositionTarget:
    return PositionTarget(msg.time_boot_ms, msg.coordinate_frame, msg.type_mask, False,
                          msg.x, msg.y, msg.z, (msg.vx, msg.vy, msg.vz),
                          (msg.afx, msg.afy, msg.afz), msg.yaw, msg.yaw_rate, msg.get_srcSystem())


def position_target_global(msg) -> PositionTarget:
    return PositionTarget(msg.time_boot_ms, msg.coordinate_frame, msg.type_mask, True,
                          msg.lat_int, msg.lon_int, msg.alt, (msg.vx, msg.vy, msg.vz),
                          (msg.afx, msg.afy, msg.afz), msg.yaw, msg.yaw_rate, msg.get_srcSystem())


def attitude_target(msg) -> AttitudeTarget:
    return AttitudeTarget(msg.time_boot_ms, msg.type_mask, tuple(msg.q),
                          (msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate),
                          msg.thrust, msg.get_srcSystem())


# POSITION_TARGET_TYPEMASK groups
MASK_POS = 0x007
MASK_VEL = 0x038
MASK_ACC = 0x1C0
MASK_FORCE_SET = 0x200
MASK_YAW = 0x400
MASK_YAW_RATE = 0x800
# ATTITUDE_TARGET_TYPEMASK
ATT_MASK_RATES = 0x07
ATT_MASK_THROTTLE = 0x40
ATT_MASK_ATTITUDE = 0x80


@dataclass(frozen=True, slots=True)
class MaskUse:
    """What a SET_POSITION_TARGET_* uses; ``kind`` None means refused (``why``), and then
    ``stop`` says whether the vehicle stops or just drops the message."""
    kind: str | None          # "pos", "posvelaccel", "velaccel", "accel"
    use_accel: bool = False
    use_yaw: bool = False
    use_yaw_rate: bool = False
    why: str = ""
    stop: bool = True


def position_mask_use(type_mask: int) -> MaskUse:
    pos = not type_mask & MASK_POS
    vel = not type_mask & MASK_VEL
    acc = not type_mask & MASK_ACC
    yaw, rate = not type_mask & MASK_YAW, not type_mask & MASK_YAW_RATE
    if type_mask & MASK_FORCE_SET and acc:
        return MaskUse(None, why="force (FORCE_SET) targets are not supported", stop=False)
    if pos and vel:
        kind = "posvelaccel"
    elif vel:
        kind = "velaccel"
    elif acc and not pos:
        kind = "accel"
    elif pos and not acc:
        kind = "pos"
    elif pos:
        return MaskUse(None, why="position with acceleration needs the velocity too")
    else:
        return MaskUse(None, why="no position, velocity or acceleration used")
    return MaskUse(kind, acc, yaw, rate)


@dataclass(frozen=True, slots=True)
class AttitudeUse:
    """What a SET_ATTITUDE_TARGET uses; ``ok`` False means refused (``why``)."""
    ok: bool
    use_attitude: bool = False
    use_rates: bool = False
    why: str = ""


def attitude_mask_use(type_mask: int, q_wxyz) -> AttitudeUse:
    if type_mask & ATT_MASK_THROTTLE:
        return AttitudeUse(False, why="thrust ignored")
    att = not type_mask & ATT_MASK_ATTITUDE
    if att:
        n2 = sum(c * c for c in q_wxyz)
        if not math.isfinite(n2) or abs(n2 - 1.0) >= 1e-3:
            return AttitudeUse(False, why="quaternion not unit length")
    rates = type_mask & ATT_MASK_RATES
    if rates not in (0, ATT_MASK_RATES):
        return AttitudeUse(False, why="some body rates ignored, not all")
    return AttitudeUse(True, att, rates == 0)
