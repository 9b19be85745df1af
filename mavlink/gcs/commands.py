"""COMMAND_LONG / COMMAND_INT: what each command means and who answers it.

``plan(req)`` turns a decoded command into one of two answers:
* ``Immediate``: the server answers at once (REQUEST_MESSAGE, SET_MESSAGE_INTERVAL, argument
  errors, unknown commands -> UNSUPPORTED), optionally followed by a message (``after``);
* ``Call``: a VehicleCommands method to run on the vehicle thread; its (MAV_RESULT, reason)
  becomes the COMMAND_ACK.

The server sends every COMMAND_ACK with target_system/target_component of the sender (MAVSDK
drops ACKs that do not match). Argument conventions follow ArduCopter 4.5: ARM with p2 = 2989
forces, DISARM with p2 = 21196 forces; DO_SET_MODE's 128 bit is not an arm request.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

ARM_FORCE_MAGIC = 2989
DISARM_FORCE_MAGIC = 21196
REPOSITION_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                               mav.MAV_FRAME_GLOBAL_INT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT})


@dataclass(frozen=True, slots=True)
class CommandRequest:
    command: int
    p1: float
    p2: float
    p3: float
    p4: float
    x: float            # COMMAND_LONG p5; COMMAND_INT x (int, e.g. lat*1e7)
    y: float            # COMMAND_LONG p6; COMMAND_INT y
    z: float            # p7
    frame: int          # COMMAND_INT frame; MAV_FRAME_GLOBAL for COMMAND_LONG
    is_int: bool
    src_system: int
    src_component: int
    confirmation: int = 0


def decode(msg) -> CommandRequest:
    if msg.get_type() == "COMMAND_INT":
        return CommandRequest(msg.command, msg.param1, msg.param2, msg.param3, msg.param4,
                              msg.x, msg.y, msg.z, msg.frame, True, msg.get_srcSystem(),
                              msg.get_srcComponent())
    return CommandRequest(msg.command, msg.param1, msg.param2, msg.param3, msg.param4,
                          msg.param5, msg.param6, msg.param7, mav.MAV_FRAME_GLOBAL, False,
                          msg.get_srcSystem(), msg.get_srcComponent(), msg.confirmation)


@dataclass(frozen=True, slots=True)
class Immediate:
    result: int
    reason: str | None = None
    after: Callable[[], None] | None = None


@dataclass(frozen=True, slots=True)
class Call:
    method: str
    args: tuple = ()
    after: Callable[[int], None] | None = None     # called with the MAV_RESULT


def _global_point(req: CommandRequest, what: str, *, out_of_range: int):
    """(lat_e7, lon_e7) of a command's x/y in a GLOBAL frame (COMMAND_INT: integers,
    COMMAND_LONG: degrees), or the Immediate refusal that names what is wrong."""
    if req.frame not in REPOSITION_FRAMES:
        return Immediate(mav.MAV_RESULT_DENIED, f"{what}: frame {req.frame} not supported, "
                                                f"use GLOBAL(_RELATIVE_ALT)_INT")
    if req.is_int:
        lat_e7, lon_e7 = int(req.x), int(req.y)
    else:
        if not (math.isfinite(req.x) and math.isfinite(req.y)):
            return Immediate(mav.MAV_RESULT_DENIED, f"{what}: latitude/longitude missing")
        lat_e7, lon_e7 = int(round(req.x * 1e7)), int(round(req.y * 1e7))
    if not (-900_000_000 <= lat_e7 <= 900_000_000
            and -1_800_000_000 <= lon_e7 <= 1_800_000_000):
        return Immediate(out_of_range, f"{what}: latitude/longitude out of range")
    return lat_e7, lon_e7


def _int_or(v: float, default: int) -> int:
    return int(v) if math.isfinite(v) else default


class CommandPlanner:
    """Maps commands to answers. ``srv`` supplies the server-side operations:
    request_message(link, msg_id, req) -> Immediate, set_message_interval(link, msg_id,
    interval_us) -> Immediate, message_interval(link, msg_id) -> Immediate,
    set_current_after(link) -> callable, mission_count() -> int, storage(p1) -> Immediate."""

    def __init__(self, srv):
        self.srv = srv

    def plan(self, link, req: CommandRequest) -> Immediate | Call:
        c = req.command
        if c == mav.MAV_CMD_COMPONENT_ARM_DISARM:
            if req.p1 == 1.0:
                return Call("arm", (int(req.p2) == ARM_FORCE_MAGIC if math.isfinite(req.p2)
                                    else False,))
            if req.p1 == 0.0:
                return Call("disarm", (int(req.p2) == DISARM_FORCE_MAGIC
                                       if math.isfinite(req.p2) else False,))
            return Immediate(mav.MAV_RESULT_DENIED, "Arm: param1 must be 1 (arm) or 0 (disarm)")
        if c == mav.MAV_CMD_DO_SET_MODE:
            base = _int_or(req.p1, 0)
            if not base & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED or not math.isfinite(req.p2):
                return Immediate(mav.MAV_RESULT_DENIED,
                                 "Mode change needs base_mode with CUSTOM_MODE_ENABLED "
                                 "and the mode number in param2")
            return Call("set_mode", (int(req.p2),))
        if c == mav.MAV_CMD_NAV_TAKEOFF:
            if not math.isfinite(req.z) or req.z <= 0.0:
                return Immediate(mav.MAV_RESULT_DENIED, "Takeoff: altitude (param7) must be > 0 m")
            return Call("takeoff", (float(req.z),))
        if c == mav.MAV_CMD_NAV_LAND:
            return Call("land")
        if c == mav.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            return Call("rtl")
        if c == mav.MAV_CMD_MISSION_START:
            return Call("mission_start", (_int_or(req.p1, 0), _int_or(req.p2, 0)))
        if c == mav.MAV_CMD_DO_REPOSITION:
            return self._reposition(req)
        if c == mav.MAV_CMD_DO_CHANGE_SPEED:
            if not (math.isfinite(req.p2) and req.p2 > 0.0):
                return Immediate(mav.MAV_RESULT_FAILED)     # ArduCopter 4.6.0: speed must be > 0
            return Call("change_speed", (float(req.p2),
                                         float(req.p1) if math.isfinite(req.p1) else 1.0))
        if c == mav.MAV_CMD_CONDITION_YAW:
            return self._condition_yaw(req)
        if c == mav.MAV_CMD_DO_SET_HOME:
            return self._set_home(req)
        if c == mav.MAV_CMD_DO_SET_MISSION_CURRENT:
            seq = _int_or(req.p1, -1)
            if not 0 < seq < self.srv.mission_count():
                return Immediate(mav.MAV_RESULT_DENIED, f"Mission has no item {seq}")
            return Call("mission_set_current", (seq,), self.srv.set_current_after(link))
        if c == mav.MAV_CMD_REQUEST_MESSAGE:
            return self.srv.request_message(link, _int_or(req.p1, -1), req)
        if c == mav.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
            return self.srv.request_message(link, mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION, req)
        if c == mav.MAV_CMD_GET_HOME_POSITION:
            return self.srv.request_message(link, mav.MAVLINK_MSG_ID_HOME_POSITION, req)
        if c == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
            return self.srv.set_message_interval(link, _int_or(req.p1, -1), req.p2)
        if c == mav.MAV_CMD_GET_MESSAGE_INTERVAL:
            return self.srv.message_interval(link, _int_or(req.p1, -1))
        if c == mav.MAV_CMD_INJECT_FAILURE:     # PX4's: p1 FAILURE_UNIT, p2 FAILURE_TYPE, p3 instance
            return Call("inject_failure", (_int_or(req.p1, -1), _int_or(req.p2, -1),
                                           _int_or(req.p3, 0)))
        if c == mav.MAV_CMD_PREFLIGHT_STORAGE:
            return self.srv.storage(_int_or(req.p1, -1))
        return Immediate(mav.MAV_RESULT_UNSUPPORTED)

    @staticmethod
    def _set_home(req: CommandRequest) -> Immediate | Call:
        """As ArduCopter 4.6 answers it (checked against the real one): param1 = 1, or latitude
        and longitude both 0, is "here"; otherwise the given point becomes home, anywhere, armed
        or not, and stays (it no longer follows the vehicle, nor moves at arming). COMMAND_LONG's
        altitude is above sea level; COMMAND_INT's follows its frame (relative = above the
        current home)."""
        if req.p1 == 1.0 or (req.x == 0 and req.y == 0):
            return Call("set_home", (None, None, 0.0, False))
        if not math.isfinite(req.z):
            return Immediate(mav.MAV_RESULT_DENIED, "Set home: altitude (param7) missing")
        point = _global_point(req, "Set home", out_of_range=mav.MAV_RESULT_FAILED)
        if isinstance(point, Immediate):
            return point
        lat_e7, lon_e7 = point
        relative = req.frame in (mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                 mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        return Call("set_home", (lat_e7, lon_e7, float(req.z), relative))

    @staticmethod
    def _condition_yaw(req: CommandRequest) -> Immediate | Call:
        """ArduCopter 4.6: p1 angle 0..360 deg, p2 rate deg/s (0 = ATC_SLEW_YAW), p3 direction
        (-1 counter-clockwise, 1 clockwise, 0 the short way; read as int8), p4 1 relative /
        0 absolute; anything else FAILED, silently."""
        if not (0.0 <= req.p1 <= 360.0 and req.p4 in (0.0, 1.0)):
            return Immediate(mav.MAV_RESULT_FAILED)
        rate = req.p2 if math.isfinite(req.p2) else 0.0
        direction = int(max(-128.0, min(127.0, req.p3))) if math.isfinite(req.p3) else 0
        return Call("condition_yaw", (float(req.p1), float(rate), direction, req.p4 == 1.0))

    @staticmethod
    def _reposition(req: CommandRequest) -> Immediate | Call:
        point = _global_point(req, "Reposition", out_of_range=mav.MAV_RESULT_DENIED)
        if isinstance(point, Immediate):
            return point
        lat_e7, lon_e7 = point
        if not math.isfinite(req.z):
            return Immediate(mav.MAV_RESULT_DENIED, "Reposition: altitude missing")
        # param2 bit 0 (MAV_DO_REPOSITION_FLAGS_CHANGE_MODE): switch to GUIDED if need be
        change_mode = bool(_int_or(req.p2, 0) & mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)
        return Call("reposition", (lat_e7, lon_e7, float(req.z), req.frame, float(req.p1),
                                   float(req.p4), change_mode))
