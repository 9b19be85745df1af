"""PX4's simulator contract (simulator_mavlink, PX4 v1.15): the simulator's messages.

What PX4 SITL (`simulator_mavlink start -c 4560+N`, airframe 10016_none_iris) expects from a
simulator, learnt from its SimulatorMavlink.cpp and measured against v1.15.4:

- PX4 connects over TCP and sends one HEARTBEAT (autopilot 12) and a COMMAND_LONG
  SET_MESSAGE_INTERVAL asking for HIL_STATE_QUATERNION every param2 us (5000).
- Every HIL_SENSOR with id 0 sets PX4's clock to its time_usec and advances its lockstep
  scheduler by one step. PX4 blocks its start-up (estimator, logger) until sim time moves,
  and its first HIL_ACTUATOR_CONTROLS only comes once they are up (~64 ms of sim time): the
  simulator freewheels sensors until then, and from the first reply on steps once per reply.
- HIL_SENSOR.fields_updated: PX4 takes a group only when ALL its bits are set: accel 0b111,
  gyro 0b111000, mag 0b111000000, baro 0b1101000000000 (abs pressure, pressure_alt and
  temperature: bits 9, 11, 12). Pressure in hPa, field in gauss. The IMU is expected at
  250 Hz (IMU_INTEG_RATE 250 in its px4-rc.simulator), so one HIL_SENSOR per 4 ms step.
- Perfectly noise-free mag or baro are flagged STALE and block arming: the scenario's sensor
  models (white noise on both) feed them.
- HIL_GPS: lat/lon degE7, alt mm, eph/epv cm, vel/vn/ve/vd cm/s, cog cdeg (65535 unknown),
  fix_type, satellites_visible; PX4 stamps it on arrival (EKF2_GPS_DELAY covers latency).
- HIL_ACTUATOR_CONTROLS: controls[i] = PX4 output i in 0..1 (all 0 while disarmed), mode
  bit 7 (128) armed, flags bit 0 lockstep; time_usec = PX4's clock when it was sent.

Motor order. PX4's 10016_none_iris: rotor 0 front-right (CA_ROTOR0_PX +, PY +) KM +0.05 (CCW),
rotor 1 back-left CCW, rotor 2 front-left CW (KM -0.05), rotor 3 back-right CW; PWM_MAIN_FUNC1..4
= Motor 1..4. Ours (jsbsim_models/quadx): 1 front-right CCW, 2 back-left CCW, 3 front-left CW,
4 back-right CW. So PX4 output i drives our motor i + 1 (MOTOR_MAP); the mapping is a table so
a frame whose order differs changes one line. The geometry (PX4's wide iris vs our square X)
is set from our model when silbridge starts PX4 (tools/autopilots/px4/sitl.py).
"""

from __future__ import annotations

import math
import struct
from typing import NamedTuple

import numpy as np

from silbridge.shm.record_structs import BARO as _BARO
from silbridge.shm.record_structs import GNSS as _GNSS
from silbridge.shm.record_structs import GT_ATT as _GT_ATT
from silbridge.shm.record_structs import GT_NAV as _GT_NAV
from silbridge.shm.record_structs import IMU as _IMU
from silbridge.shm.record_structs import MAG as _MAG
from silbridge.shm.records import RECORD_SIZE, Kind

from silbridge.mavlink.hil.hil_codec import SensorEncoder

FIELDS_ACCEL = 0b111
FIELDS_GYRO = 0b111000
FIELDS_MAG = 0b111000000
FIELDS_BARO = 0b1101000000000
STEP_HZ = 250                  # PX4's IMU_INTEG_RATE for simulators
STATE_INTERVAL_US = 5000       # what PX4 v1.15 asks for; used until it asks
MOTOR_MAP = (0, 1, 2, 3)       # PX4 output index of our motors 1..4
MOTORS = 4
MODE_ARMED = 128
FLAG_LOCKSTEP = 1
MSG_HIL_STATE_QUATERNION = 115
MSG_HIL_ACTUATOR_CONTROLS = 93
CMD_SET_MESSAGE_INTERVAL = 511
SIM_SYSID, SIM_COMPID = 1, 51   # our simulator's MAVLink identity on PX4's simulator link
PX4_AUTOPILOT = 12

_IMU_K, _BARO_K, _MAG_K, _GNSS_K = int(Kind.IMU), int(Kind.BARO), int(Kind.MAG), int(Kind.GNSS)
_GT_ATT_K, _GT_NAV_K = int(Kind.GT_ATT), int(Kind.GT_NAV)
_KEPT = frozenset((_BARO_K, _MAG_K, _GNSS_K, _GT_ATT_K, _GT_NAV_K))


def pressure_altitude_m(pa: float) -> float:
    """ISA pressure altitude [m] (PX4 reads HIL_SENSOR.pressure_alt with the baro group)."""
    return 44330.77 * (1.0 - (pa / 101325.0) ** 0.190263)


def controls_to_pwm_us(controls) -> list[int]:
    """HIL_ACTUATOR_CONTROLS controls (PX4 outputs, 0..1) -> our motors 1..4 in us."""
    out = []
    for i in MOTOR_MAP:
        c = controls[i]
        c = 0.0 if not math.isfinite(c) else min(1.0, max(0.0, c))
        out.append(int(round(1000.0 + 1000.0 * c)))
    return out


class Px4Controls(NamedTuple):
    """HIL_ACTUATOR_CONTROLS as the lockstep loop reads it, built from the frame's wire values
    (mavlink/v2_frames.py) instead of a pymavlink message object, once per PX4 step."""
    time_usec: int
    flags: int
    controls: tuple
    mode: int

    @classmethod
    def of_wire(cls, v: tuple) -> "Px4Controls":
        return cls(v[0], v[1], v[2:18], v[18])    # wire order: time_usec, flags, controls, mode

    def get_msgId(self) -> int:                   # noqa: N802 - pymavlink's name
        return MSG_HIL_ACTUATOR_CONTROLS

    def get_type(self) -> str:
        return "HIL_ACTUATOR_CONTROLS"


class StepAccumulator:
    """The records of the physics steps that make one PX4 step, reduced to what PX4 reads.

    IMU: the mean of the samples (a boxcar, as an IMU FIFO read averages); baro, mag, GNSS:
    the newest sample if one came; truth: the newest GT_ATT and GT_NAV. A kept record is its
    step's bytes and its offset there (no copy: the bytes are this step's own)."""

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        self.imu: list[tuple] = []                # (ax, ay, az, gx, gy, gz) per sample
        self.latest: dict[int, tuple] = {}        # kind -> (bytes, offset)

    @property
    def n_imu(self) -> int:
        return len(self.imu)

    def add(self, recs: np.ndarray) -> None:
        raw = recs.tobytes()
        for off in range(0, len(raw), RECORD_SIZE):
            k = raw[off] | (raw[off + 1] << 8)    # the uint16 kind
            if k == _IMU_K:
                self.imu.append(_IMU.unpack_from(raw, off))
            elif k in _KEPT:
                self.latest[k] = (raw, off)

    def imu_mean(self) -> tuple:
        """(ax, ay, az, gx, gy, gz), summed in sample order (the sum's rounding is part of
        what PX4 receives, so no reordering or compensated sum)."""
        s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        for v in self.imu:
            s0 += v[0]
            s1 += v[1]
            s2 += v[2]
            s3 += v[3]
            s4 += v[4]
            s5 += v[5]
        n = len(self.imu)
        return s0 / n, s1 / n, s2 / n, s3 / n, s4 / n, s5 / n

    def fields(self, kind: int, layout: struct.Struct):
        """The newest record of kind unpacked with layout, or None if none came."""
        got = self.latest.get(kind)
        return None if got is None else layout.unpack_from(got[0], got[1])


class Px4SensorEncoder:
    """One PX4 step -> frames: `encode`: HIL_GPS when a fix came, HIL_SENSOR (what PX4's
    lockstep waits for); `encode_truth`: HIL_STATE_QUATERNION at PX4's requested interval."""

    def __init__(self, codec, origin=(0, 0, 0)):
        self.codec = codec
        self._truth = SensorEncoder(codec, origin)    # HIL_GPS / HIL_STATE_QUATERNION layout
        self._sensor = self._truth.sensor_frames
        self.state_interval_us = STATE_INTERVAL_US
        self._next_state_us = 0
        self.temperature_c = 20.0
        self.sent = {"HIL_SENSOR": 0, "HIL_GPS": 0, "HIL_STATE_QUATERNION": 0}
        self._last_acc = (0.0, 0.0, -9.80665)
        self._last_gyro = (0.0, 0.0, 0.0)

    def set_interval(self, msg_id: int, interval_us: float) -> bool:
        """SET_MESSAGE_INTERVAL from PX4; True if it was about a message we send."""
        if int(msg_id) != MSG_HIL_STATE_QUATERNION:
            return False
        # MAVLink: -1 = stop, 0 = default; PX4 asks 5000 us.
        self.state_interval_us = (-1 if interval_us < 0 else
                                  STATE_INTERVAL_US if interval_us == 0 else int(interval_us))
        return True

    def encode(self, acc: StepAccumulator, step_us: int, out: list) -> None:
        if acc.imu:
            a0, a1, a2, g0, g1, g2 = acc.imu_mean()
            self._last_acc, self._last_gyro = (a0, a1, a2), (g0, g1, g2)
        else:   # no sample this step (IMU slower than PX4's step): hold the last one
            (a0, a1, a2), (g0, g1, g2) = self._last_acc, self._last_gyro
        bits = FIELDS_ACCEL | FIELDS_GYRO
        m = acc.fields(_MAG_K, _MAG)
        if m is not None:
            bits |= FIELDS_MAG
        else:
            m = (0.0, 0.0, 0.0)
        baro = acc.fields(_BARO_K, _BARO)
        hpa = alt = 0.0
        if baro is not None:
            pa, self.temperature_c = baro
            hpa, alt = pa / 100.0, pressure_altitude_m(pa)
            bits |= FIELDS_BARO
        gnss = acc.fields(_GNSS_K, _GNSS)
        if gnss is not None:
            out.append(self._truth.gps_frame(step_us, *gnss))
            self.sent["HIL_GPS"] += 1
        out.append(self._sensor.pack(step_us, a0, a1, a2, g0, g1, g2, m[0], m[1], m[2], hpa, 0.0,
                                     alt, self.temperature_c, bits, 0))
        self.sent["HIL_SENSOR"] += 1

    def encode_truth(self, acc: StepAccumulator, step_us: int, out: list) -> None:
        """HIL_STATE_QUATERNION of the step, when PX4's requested interval has passed."""
        iv = self.state_interval_us
        if iv >= 0 and step_us >= self._next_state_us:
            att, nav = acc.fields(_GT_ATT_K, _GT_ATT), acc.fields(_GT_NAV_K, _GT_NAV)
            if att is not None and nav is not None:
                out.append(self._truth.state_frame(step_us, att[0:4], att[4:7], att[7:10],
                                                   nav[0:3], nav[3:6]))
                self.sent["HIL_STATE_QUATERNION"] += 1
                self._next_state_us = step_us + iv
