"""GUIDED/offboard inputs decoded into the vehicle's setpoint types.

SET_POSITION_TARGET_LOCAL_NED (frames LOCAL_NED, LOCAL_OFFSET_NED, BODY_NED, BODY_OFFSET_NED),
SET_POSITION_TARGET_GLOBAL_INT (the global frames, float or _INT form) and SET_ATTITUDE_TARGET
are passed through with their type_mask untouched: what to follow is the vehicle's decision
(ArduCopter ignores them while landed and times out GUIDED after GUID_TIMEOUT). A setpoint in a
frame we do not fly returns None and is counted by the caller.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import AttitudeTarget, PositionTarget

LOCAL_FRAMES = frozenset({mav.MAV_FRAME_LOCAL_NED, mav.MAV_FRAME_LOCAL_OFFSET_NED,
                          mav.MAV_FRAME_BODY_NED, mav.MAV_FRAME_BODY_OFFSET_NED})
GLOBAL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                           mav.MAV_FRAME_GLOBAL_INT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                           mav.MAV_FRAME_GLOBAL_TERRAIN_ALT, mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})


def position_target_local(msg) -> PositionTarget | None:
    if msg.coordinate_frame not in LOCAL_FRAMES:
        return None
    return PositionTarget(msg.time_boot_ms, msg.coordinate_frame, msg.type_mask, False,
                          msg.x, msg.y, msg.z, (msg.vx, msg.vy, msg.vz),
                          (msg.afx, msg.afy, msg.afz), msg.yaw, msg.yaw_rate, msg.get_srcSystem())


def position_target_global(msg) -> PositionTarget | None:
    if msg.coordinate_frame not in GLOBAL_FRAMES:
        return None
    return PositionTarget(msg.time_boot_ms, msg.coordinate_frame, msg.type_mask, True,
                          msg.lat_int, msg.lon_int, msg.alt, (msg.vx, msg.vy, msg.vz),
                          (msg.afx, msg.afy, msg.afz), msg.yaw, msg.yaw_rate, msg.get_srcSystem())


def attitude_target(msg) -> AttitudeTarget:
    return AttitudeTarget(msg.time_boot_ms, msg.type_mask, tuple(msg.q),
                          (msg.body_roll_rate, msg.body_pitch_rate, msg.body_yaw_rate),
                          msg.thrust, msg.get_srcSystem())
