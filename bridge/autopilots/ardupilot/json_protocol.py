"""ArduPilot SITL's JSON physics protocol: the servo packet in, the state line out.

`arducopter --model JSON` sends one UDP datagram per physics frame to the
physics program (default 127.0.0.1:9002, +10 per --instance), little-endian,
no padding (libraries/SITL/SIM_JSON.h, struct servo_packet):

    uint16 magic        18458 with 16 channels; 29569 with 32 (SERVO_32_ENABLE)
    uint16 frame_rate   SITL's physics rate [Hz] (SIM_RATE_HZ)
    uint32 frame_count  +1 per new frame; a resend after a 1 s timeout repeats it
    uint16 pwm[16|32]   servo outputs [us]; motors read 1000 while disarmed

The physics answers the packet's source address with one JSON object framed
by a newline before and after. SITL's parser is not a JSON parser: it finds
each key with strstr, skips `"key":` and reads the number or `[a, b, c]`
right there, so values follow the colon without a space and no key may be a
substring of an earlier one. Required: timestamp [s], imu.gyro [rad/s, body
FRD], imu.accel_body [m/s^2 specific force, z = -9.81 at rest], position [m
NED from home], velocity [m/s NED]; attitude as quaternion [w, x, y, z] or
Euler [roll, pitch, yaw] (newer SITLs prefer the quaternion; we send both so
older builds that only read `attitude` work too).

Motor order: ArduCopter quad X (FRAME_CLASS 1, FRAME_TYPE 1) drives SERVO1..4
as motors 1..4 = front-right CCW, back-left CCW, front-left CW, back-right
CW: the Simulator's order, so pwm[0:4] go to the Simulator unchanged.
"""

from __future__ import annotations

import math
import struct

from silbridge.bridge.errors import SimulatorError

MAGIC_16 = 18458
MAGIC_32 = 29569
DEFAULT_PORT = 9002          # SITL instance 0; instance N uses 9002 + 10 N
PORT_STRIDE = 10
_HEAD = struct.Struct("<HHI")
PACKET_16 = struct.Struct("<HHI16H")   # 40 bytes
PACKET_32 = struct.Struct("<HHI32H")   # 72 bytes
MOTORS = 4
PWM_MIN_US = 1000
PWM_MAX_US = 2000


class ArduPilotProtocolError(SimulatorError):
    """A datagram that is not an ArduPilot SITL JSON servo packet."""

    user_facing = True


class ServoPacket:
    """One decoded servo packet."""

    __slots__ = ("magic", "frame_rate_hz", "frame_count", "pwm_us")

    def __init__(self, magic: int, frame_rate_hz: int, frame_count: int, pwm_us: tuple):
        self.magic = magic
        self.frame_rate_hz = frame_rate_hz
        self.frame_count = frame_count
        self.pwm_us = pwm_us

    @property
    def channels(self) -> int:
        return len(self.pwm_us)


def sitl_port(instance: int) -> int:
    """The UDP port SITL instance N sends its servo packets to."""
    return DEFAULT_PORT + PORT_STRIDE * int(instance)


def decode_servo_packet(data: bytes, source=None) -> ServoPacket:
    """Bytes -> ServoPacket; a wrong magic or size raises ArduPilotProtocolError."""
    where = f" from {source[0]}:{source[1]}" if source else ""
    if len(data) < _HEAD.size:
        raise ArduPilotProtocolError(
            f"{len(data)}-byte datagram{where} is too short for an ArduPilot servo packet; "
            "only `arducopter --model JSON` may send to the JSON physics port")
    magic, rate, count = _HEAD.unpack_from(data)
    if magic == MAGIC_16:
        layout = PACKET_16
    elif magic == MAGIC_32:
        layout = PACKET_32
    else:
        raise ArduPilotProtocolError(
            f"datagram{where} has magic {magic}, not {MAGIC_16} (16 channels) or {MAGIC_32} "
            "(32 channels): is it ArduPilot SITL started with --model JSON? Check that "
            "nothing else sends to this port")
    if len(data) != layout.size:
        raise ArduPilotProtocolError(
            f"servo packet{where} with magic {magic} is {len(data)} bytes, expected "
            f"{layout.size}: mismatched ArduPilot version or a truncated datagram")
    fields = layout.unpack(data)
    return ServoPacket(magic, rate, count, fields[3:])


def encode_servo_packet(frame_count: int, pwm_us, frame_rate_hz: int = 1000,
                        channels: int = 16) -> bytes:
    """What SITL sends (the fake SITL of the tests uses it)."""
    pwm = list(pwm_us)[:channels]
    pwm += [0] * (channels - len(pwm))
    if channels == 16:
        return PACKET_16.pack(MAGIC_16, frame_rate_hz, frame_count & 0xFFFFFFFF, *pwm)
    if channels == 32:
        return PACKET_32.pack(MAGIC_32, frame_rate_hz, frame_count & 0xFFFFFFFF, *pwm)
    raise ValueError(f"channels must be 16 or 32, got {channels}")


def motor_pwm_us(packet: ServoPacket) -> tuple:
    """The four motor pulse widths for Simulator.step, clamped to 1000..2000 us.

    SITL reports 0 on a channel it has not started driving yet (early boot):
    read as 1000 us, motor stopped, like an ESC without a pulse."""
    out = []
    for us in packet.pwm_us[:MOTORS]:
        out.append(float(min(max(us, PWM_MIN_US), PWM_MAX_US)))
    return tuple(out)


# The reply, keys in SITL's table order, no space after any colon (SITL reads the value
# at colon + 1), valid JSON for finite values. One %-format of a flat tuple: a json.dumps
# per packet costs 3x more, and repr() of each number 4x more (~75 us per packet on the
# 2-core VM; this ~20 us). Digits: the timestamp exact (repr: SITL's clock advances by
# its differences); sensor and attitude values 9 significant digits (they are float32
# in the records: exact); position and velocity 12 (doubles: um at 1000 km).
_STATE_FMT = ('\n{"timestamp":%r,"imu":{"gyro":[%.9g,%.9g,%.9g],"accel_body":[%.9g,%.9g,%.9g]},'
              '"position":[%.12g,%.12g,%.12g],"attitude":[%.9g,%.9g,%.9g],'
              '"quaternion":[%.9g,%.9g,%.9g,%.9g],"velocity":[%.12g,%.12g,%.12g]}\n')


def encode_values(values: tuple) -> bytes:
    """The reply line from 20 floats in _STATE_FMT's order: timestamp, gyro, accel,
    position, euler, quaternion, velocity (the physics' hot path)."""
    # NaN or inf would be read by SITL's atof as 0 or garbage: never send one.
    if not math.isfinite(sum(values)):
        raise non_finite(str(values))
    return (_STATE_FMT % values).encode()


def non_finite(where: str) -> ArduPilotProtocolError:
    """The error for a state that must not reach SITL (C's json_reply gives None for it)."""
    return ArduPilotProtocolError(f"non-finite value in the physics state {where}: the "
                                  "simulation diverged; stop and check the scenario")


def encode_state(timestamp_s: float, gyro_frd_rad_s, accel_frd_m_s2, pos_ned_m, vel_ned_m_s,
                 q_wxyz, euler_rad) -> bytes:
    """The reply line: newline, one compact JSON object, newline."""
    values = (float(timestamp_s), *map(float, gyro_frd_rad_s), *map(float, accel_frd_m_s2),
              *map(float, pos_ned_m), *map(float, euler_rad), *map(float, q_wxyz),
              *map(float, vel_ned_m_s))
    if len(values) != 20:
        raise ValueError(f"encode_state wants 20 numbers, got {len(values)}")
    return encode_values(values)
