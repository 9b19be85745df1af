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
is set from our model when silbridge starts PX4 (tools/autopilots/sitl_px4.py).
"""

from __future__ import annotations

import math
import struct

import numpy as np

from silbridge.shm.records import (
    BARO_DTYPE,
    GNSS_DTYPE,
    GT_ATT_DTYPE,
    GT_NAV_DTYPE,
    MAG_DTYPE,
    RECORD_SIZE,
    Kind,
)

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
CMD_SET_MESSAGE_INTERVAL = 511
PX4_AUTOPILOT = 12

_KIND = struct.Struct("<H")
_IMU = struct.Struct("<24x6f")          # accel_frd_m_s2[3], gyro_frd_rad_s[3]
_IMU_K, _BARO_K, _MAG_K, _GNSS_K = int(Kind.IMU), int(Kind.BARO), int(Kind.MAG), int(Kind.GNSS)
_GT_ATT_K, _GT_NAV_K = int(Kind.GT_ATT), int(Kind.GT_NAV)
_DTYPES = {_BARO_K: BARO_DTYPE, _MAG_K: MAG_DTYPE, _GNSS_K: GNSS_DTYPE, _GT_ATT_K: GT_ATT_DTYPE,
           _GT_NAV_K: GT_NAV_DTYPE}


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


class StepAccumulator:
    """The records of the physics steps that make one PX4 step, reduced to what PX4 reads.

    IMU: the mean of the samples (a boxcar, as an IMU FIFO read averages); baro, mag, GNSS:
    the newest sample if one came; truth: the newest GT_ATT and GT_NAV."""

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        self.sums = [0.0] * 6
        self.n_imu = 0
        self.latest: dict[int, bytes] = {}

    def add(self, recs: np.ndarray) -> None:
        raw = recs.tobytes()
        sums = self.sums
        for off in range(0, len(raw), RECORD_SIZE):
            k = _KIND.unpack_from(raw, off)[0]
            if k == _IMU_K:
                for j, v in enumerate(_IMU.unpack_from(raw, off)):
                    sums[j] += v
                self.n_imu += 1
            elif k in _DTYPES:
                self.latest[k] = raw[off:off + RECORD_SIZE]

    def record(self, kind: int):
        raw = self.latest.get(kind)
        return None if raw is None else np.frombuffer(raw, dtype=_DTYPES[kind])[0]


class Px4SensorEncoder:
    """One PX4 step -> frames: `encode`: HIL_GPS when a fix came, HIL_SENSOR (what PX4's
    lockstep waits for); `encode_truth`: HIL_STATE_QUATERNION at PX4's requested interval."""

    def __init__(self, codec, origin=(0, 0, 0)):
        self.codec = codec
        self._truth = SensorEncoder(codec, origin)    # HIL_GPS / HIL_STATE_QUATERNION layout
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
        c = self.codec
        if acc.n_imu:
            n = acc.n_imu
            a = tuple(s / n for s in acc.sums[0:3])
            g = tuple(s / n for s in acc.sums[3:6])
            self._last_acc, self._last_gyro = a, g
        else:   # no sample this step (IMU slower than PX4's step): hold the last one
            a, g = self._last_acc, self._last_gyro
        bits = FIELDS_ACCEL | FIELDS_GYRO
        mag = acc.record(_MAG_K)
        m = (0.0, 0.0, 0.0)
        if mag is not None:
            m = mag["field_frd_gauss"].tolist()
            bits |= FIELDS_MAG
        baro = acc.record(_BARO_K)
        hpa = alt = 0.0
        if baro is not None:
            pa = float(baro["pressure_pa"])
            hpa, alt = pa / 100.0, pressure_altitude_m(pa)
            self.temperature_c = float(baro["temperature_c"])
            bits |= FIELDS_BARO
        gnss = acc.record(_GNSS_K)
        if gnss is not None:
            out.append(self._truth._gps_frame(gnss, step_us))
            self.sent["HIL_GPS"] += 1
        out.append(c.hil_sensor_encode(step_us, a[0], a[1], a[2], g[0], g[1], g[2], m[0], m[1],
                                       m[2], hpa, 0.0, alt, self.temperature_c, bits,
                                       0).pack(c))
        self.sent["HIL_SENSOR"] += 1

    def encode_truth(self, acc: StepAccumulator, step_us: int, out: list) -> None:
        """HIL_STATE_QUATERNION of the step, when PX4's requested interval has passed."""
        iv = self.state_interval_us
        if iv >= 0 and step_us >= self._next_state_us:
            att, nav = acc.record(_GT_ATT_K), acc.record(_GT_NAV_K)
            if att is not None and nav is not None:
                out.append(self._truth._state_frame(att, nav, step_us))
                self.sent["HIL_STATE_QUATERNION"] += 1
                self._next_state_us = step_us + iv
