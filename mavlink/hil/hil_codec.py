"""Simulator -> FC direction of the HIL transport: shm records <-> MAVLink 2 HIL messages.

`SensorEncoder` (bridge side) turns one physics step of records into frames; `SensorDecoder`
(FC side) turns the frames back into the same records, in the same order, one step at a time.

Per physics step the bridge sends, in this order:
  SET_ATTITUDE_TARGET + SET_POSITION_TARGET_LOCAL_NED  when the step has a SETPOINT record
  HIL_GPS                                               when it has a GNSS record
  HIL_SENSOR x n    one per IMU sample, time_usec = the sample's time; the step's BARO / MAG
                    ride on the last one (fields_updated bits 9 and 12 / 6-8; a step with no
                    IMU sample sends one HIL_SENSOR with only those bits), `id` = 0
  BATTERY_STATUS                                        when it has a BATTERY record
                                                        (the pack, 10 Hz; hil_battery.py)
  ESC_TELEMETRY_1_TO_4 (and _5_TO_8)                    when it has ESC records (see below)
  HIL_STATE_QUATERNION  ground truth (GT_ATT + GT_NAV); closes the step (STEP_END)
The decoder rebuilds the step in the contract's order (IMU..., GT_ATT, GT_NAV, BARO, MAG, GNSS,
SETPOINT, BATTERY, ESC...), numbers each kind from 0 as the bridge does, and flags the last record
STEP_END.

ESC telemetry rides in ArduPilot's ESC_TELEMETRY_1_TO_4 (#11030, motors 1-4; _5_TO_8 for 5-8):
the record is quantised at the source to what a BLHeli_32 ESC reports (bridge/esc_telemetry.py:
whole degC, 0.01 V, 0.01 A, whole mAh, whole rpm) and this message carries exactly those five
quantities in exactly those units, four ESCs a frame, so the FC rebuilds each record bit for
bit. The common dialect's ESC_STATUS (#291) carries rpm, voltage and current only; temperature
would need ESC_INFO (#290) beside it and consumption has no field in either. The records' time
is the step's (ESC reports are made at physics-step times), so the message needs no timestamp.
`count` carries each ESC's report number (1-based, never 0): a slot with count 0 is an ESC
that did not report.

Exact where promised (the bridge quantises at the source, see hil_quant.py): IMU accel, gyro
and sample times; BARO pressure; MAG field; GNSS lat, lon, alt, velocity, eph, epv, fix type,
satellites; GT_ATT quaternion and rates; GT_NAV down position and velocity; SETPOINT (exact
float32 angles ride in SET_ATTITUDE_TARGET's body-rate fields, which its type_mask marks
ignored, so a standard receiver still reads the quaternion). Lossy and unused by the FC core:
GT_ATT specific force (int16 mG), GT_NAV north/east (via degE7 about the origin, ~1 cm) and
on_ground (not carried), IMU die temperature on a sample that shares its message with the
barometer. IMU sample times travel as whole microseconds (time_usec); knowing the IMU rate
from the bridge's configuration, the decoder rebuilds the exact nanoseconds (32 kHz: 31.25 us).

Two HIL_SENSOR fields a multirotor leaves unset (diff_pressure, pressure_alt; their
fields_updated bits stay clear) carry the low 48 bits of the bridge's CLOCK_MONOTONIC at
publish as two exact 24-bit integers, so the FC measures sensor -> FC latency as over shared
memory (meaningful on one machine). From a simulator that is not a silbridge bridge the decoder
stamps arrival time instead, closes a step at every HIL_SENSOR (PX4's lockstep unit) and
ignores those two fields.

Bad input raises HilInputError: NaN in a used field, or time going backwards.
"""

from __future__ import annotations

import math
import struct

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm.records import (
    BARO_DTYPE,
    BATTERY_DTYPE,
    ESC_DTYPE,
    FLAG_STEP_END,
    FLAGS_OFFSET,
    GNSS_DTYPE,
    GT_ATT_DTYPE,
    GT_NAV_DTYPE,
    IMU_DTYPE,
    KIND_BARO,
    KIND_BATTERY,
    KIND_ESC,
    KIND_GNSS,
    KIND_GT_ATT,
    KIND_GT_NAV,
    KIND_IMU,
    KIND_MAG,
    KIND_SETPOINT,
    MAG_DTYPE,
    SETPOINT_DTYPE,
    Kind,
    record_struct,
)

from silbridge.mavlink.hil import hil_battery
from silbridge.mavlink.hil.hil_errors import HilInputError
from silbridge.mavlink.v2_frames import V2Frames
from silbridge.shm.records import NS_PER_S as _NS

_G0 = 9.80665
_M_PER_DEG = 6378137.0 * math.pi / 180.0     # spherical metres per degree (north/east, lossy)
_LOW24 = (1 << 24) - 1
_LOW48 = (1 << 48) - 1

# HIL_SENSOR.fields_updated bits
UPD_ACCEL = 0x007
UPD_GYRO = 0x038
UPD_MAG = 0x1C0
UPD_ABS_PRESSURE = 0x200
UPD_TEMPERATURE = 0x1000
UPD_IMU = UPD_ACCEL | UPD_GYRO
# SET_ATTITUDE_TARGET type_mask: body rates ignored (they carry the exact Euler angles),
# thrust ignored; bit 7 = attitude ignored.
ATT_IGNORE_RATES_THRUST = 0x07 | 0x40
ATT_IGNORE_ATTITUDE = 0x80
# SET_POSITION_TARGET_LOCAL_NED type_mask: everything ignored but z and yaw, which follow the
# setpoint's mask bits.
POS_IGNORE_ALL_BUT_Z_YAW = 0x1 | 0x2 | 0x8 | 0x10 | 0x20 | 0x40 | 0x80 | 0x100 | 0x800
POS_IGNORE_Z = 0x4
POS_IGNORE_YAW = 0x400
MAV_FRAME_LOCAL_NED = 1

# The records of one step other than IMU samples, by kind: the view that reads each.
_STEP_VIEWS = {KIND_BARO: BARO_DTYPE, KIND_MAG: MAG_DTYPE, KIND_GNSS: GNSS_DTYPE,
               KIND_SETPOINT: SETPOINT_DTYPE, KIND_GT_ATT: GT_ATT_DTYPE, KIND_GT_NAV: GT_NAV_DTYPE,
               KIND_BATTERY: BATTERY_DTYPE}

# Whole 64-byte slots, packed field by field in slot order (shm/records.py declares them).
_S_IMU, _S_BARO, _S_MAG, _S_GNSS, _S_GT_ATT, _S_GT_NAV, _S_SETPOINT = (record_struct(k) for k in (
    Kind.IMU, Kind.BARO, Kind.MAG, Kind.GNSS, Kind.GT_ATT, Kind.GT_NAV, Kind.SETPOINT))
_F32 = struct.Struct("<f")

# Message ids the FC side dispatches on (the dialect's numbers, not retyped).
_ID_HIL_SENSOR = mav.MAVLINK_MSG_ID_HIL_SENSOR
_ID_HIL_STATE_QUATERNION = mav.MAVLINK_MSG_ID_HIL_STATE_QUATERNION
_ID_HIL_GPS = mav.MAVLINK_MSG_ID_HIL_GPS
_ID_SET_ATTITUDE_TARGET = mav.MAVLINK_MSG_ID_SET_ATTITUDE_TARGET
_ID_SET_POSITION_TARGET_LOCAL_NED = mav.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED
# ESC telemetry frames by first motor index (4 ESCs a frame).
_ESC_MSGS = {0: mav.MAVLink_esc_telemetry_1_to_4_message,
             4: mav.MAVLink_esc_telemetry_5_to_8_message}
_ID_ESC_FIRST = {cls.id: first for first, cls in _ESC_MSGS.items()}
_S_ESC = record_struct(Kind.ESC)
_S_BATTERY = hil_battery.SLOT
# Every message id SensorDecoder.feed consumes (the FC end routes these to it).
DECODED_IDS = frozenset({_ID_HIL_SENSOR, _ID_HIL_STATE_QUATERNION, _ID_HIL_GPS,
                         _ID_SET_ATTITUDE_TARGET, _ID_SET_POSITION_TARGET_LOCAL_NED,
                         *_ID_ESC_FIRST, hil_battery.ID_BATTERY_STATUS})
_U16 = 65535


def _u16(x: float) -> int:
    """x rounded into a u16 field (ArduPilot constrains to 0..UINT16_MAX the same way)."""
    return min(_U16, max(0, round(x)))


def f32(x: float) -> float:
    """x rounded to float32 (what a record field holds)."""
    return _F32.unpack(_F32.pack(x))[0]


def wall_fields(wall_ns: int) -> tuple[float, float]:
    """The low 48 bits of a monotonic time as two exact float32 integers."""
    w = wall_ns & _LOW48
    return float(w & _LOW24), float(w >> 24)


def wall_from_fields(lo: float, hi: float, now_ns: int) -> int:
    """Undo wall_fields against this machine's monotonic clock (sent less than 78 h ago)."""
    w = (int(hi) << 24) | int(lo)
    return now_ns - ((now_ns - w) & _LOW48)


def euler_to_quat(roll: float, pitch: float, yaw: float) -> tuple:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


class SensorEncoder:
    """Bridge side: records of physics steps -> HIL frames (see module docstring)."""

    def __init__(self, codec, origin=(0, 0, 0)):
        self.codec = codec
        self.origin = origin          # (lat_e7, lon_e7, alt_mm) of NED zero
        self.messages = 0
        # The frames of the hot path, packed as msg.pack(codec) would (mavlink/v2_frames.py).
        self.sensor_frames = V2Frames(codec, mav.MAVLink_hil_sensor_message)
        self._gps = V2Frames(codec, mav.MAVLink_hil_gps_message)
        self._state = V2Frames(codec, mav.MAVLink_hil_state_quaternion_message)
        self._esc_reports = [0] * 8     # ESC reports sent per motor (ESC_TELEMETRY count)

    def encode(self, recs: np.ndarray, wall_ns: int, out: list) -> None:
        """Append the frames of `recs` (whole steps, any number) to the list out."""
        kinds = recs["kind"]
        ends = np.flatnonzero(recs["flags"] & FLAG_STEP_END)
        start = 0
        for end in ends.tolist():
            self._step(recs[start:end + 1], kinds[start:end + 1], wall_ns, out)
            start = end + 1
        if start < len(recs):          # an unterminated tail: send it as its own step
            self._step(recs[start:], kinds[start:], wall_ns, out)

    def _step(self, recs, kinds, wall_ns: int, out: list) -> None:
        lo, hi = wall_fields(wall_ns)
        imu_idx = np.flatnonzero(kinds == KIND_IMU)
        found = {}                  # kind -> the step's (last) record of it
        for i in np.flatnonzero(kinds != KIND_IMU).tolist():
            k = int(kinds[i])
            view = _STEP_VIEWS.get(k)
            if view is not None:
                found[k] = recs[i:i + 1].view(view)[0]
        baro, mag, gnss = found.get(KIND_BARO), found.get(KIND_MAG), found.get(KIND_GNSS)
        sp, att, nav = found.get(KIND_SETPOINT), found.get(KIND_GT_ATT), found.get(KIND_GT_NAV)
        step_us = int(recs["sim_ns"][-1]) // 1000
        n = 0
        if sp is not None:
            out.append(self._setpoint_frames(sp, step_us))
            n += 2
        if gnss is not None:
            out.append(self._gps_frame(gnss, step_us))
            n += 1
        if len(imu_idx):
            imu = recs[imu_idx].view(IMU_DTYPE)
            t_us = (imu["sim_ns"] // 1000).tolist()
            acc = imu["accel_frd_m_s2"].tolist()
            gyr = imu["gyro_frd_rad_s"].tolist()
            temp = imu["temperature_c"].tolist()
            last = len(t_us) - 1
            pack = self.sensor_frames.pack
            for j in range(last):
                a, g = acc[j], gyr[j]
                out.append(pack(t_us[j], a[0], a[1], a[2], g[0], g[1], g[2], 0.0, 0.0, 0.0, 0.0,
                                lo, hi, temp[j], UPD_IMU, 0))
            a, g = acc[last], gyr[last]
            out.append(self._sensor_frame(t_us[last], a, g, temp[last], UPD_IMU, baro, mag, lo,
                                          hi))
            n += last + 1
        elif baro is not None or mag is not None:
            # Stamped with their own time: a link fault may deliver them steps late.
            t_us = max(int(r["sim_ns"]) for r in (baro, mag) if r is not None) // 1000
            out.append(self._sensor_frame(t_us, (0.0,) * 3, (0.0,) * 3, 0.0, 0, baro, mag,
                                          lo, hi))
            n += 1
        batt = found.get(KIND_BATTERY)
        if batt is not None:
            out.append(hil_battery.battery_frame(batt, self.codec))
            n += 1
        esc_idx = np.flatnonzero(kinds == KIND_ESC)
        if len(esc_idx):
            frames = self.esc_frames(recs[esc_idx].view(ESC_DTYPE))
            out.extend(frames)
            n += len(frames)
        if att is not None or nav is not None:
            out.append(self._state_frame(att, nav, step_us))
            n += 1
        self.messages += n

    def esc_frames(self, esc) -> list:
        """ESC_TELEMETRY_1_TO_4 / _5_TO_8 frames of one step's ESC records (the message's
        units: degC, cV, cA, mAh, rpm; each u16 clamped as ArduPilot sends it)."""
        cols = [esc[k].tolist() for k in ("temperature_c", "voltage_v", "current_a",
                                          "consumption_mah", "rpm")]
        frames: dict[int, list] = {}
        for i, m in enumerate(esc["motor"].tolist()):
            first = m // 4 * 4
            if first not in _ESC_MSGS:
                continue
            f = frames.setdefault(first, [[0] * 4 for _ in range(6)])
            j = m - first
            f[0][j] = min(255, max(0, round(cols[0][i])))
            f[1][j] = _u16(cols[1][i] * 100.0)
            f[2][j] = _u16(cols[2][i] * 100.0)
            f[3][j] = _u16(cols[3][i])
            f[4][j] = _u16(cols[4][i])
            f[5][j] = self._esc_reports[m] % _U16 + 1     # never 0: 0 marks a silent slot
            self._esc_reports[m] += 1
        return [_ESC_MSGS[first](*f).pack(self.codec) for first, f in sorted(frames.items())]

    def _sensor_frame(self, t_us, a, g, temp_c, bits, baro, mag, lo, hi) -> bytes:
        m = (0.0, 0.0, 0.0)
        pressure_hpa = 0.0
        if mag is not None:
            m = mag["field_frd_gauss"].tolist()
            bits |= UPD_MAG
        if baro is not None:
            pressure_hpa = float(baro["pressure_pa"]) / 100.0
            temp_c = float(baro["temperature_c"])
            bits |= UPD_ABS_PRESSURE | UPD_TEMPERATURE
        return self.sensor_frames.pack(t_us, a[0], a[1], a[2], g[0], g[1], g[2], m[0], m[1], m[2],
                                       pressure_hpa, lo, hi, temp_c, bits, 0)

    def _gps_frame(self, g, t_us) -> bytes:
        return self.gps_frame(t_us, int(g["lat_e7"]), int(g["lon_e7"]), int(g["alt_mm"]),
                              *g["vel_ned_m_s"].tolist(), int(g["eph_cm"]), int(g["epv_cm"]),
                              int(g["fix_type"]), int(g["satellites"]))

    def gps_frame(self, t_us, lat_e7, lon_e7, alt_mm, vn, ve, vd, eph_cm, epv_cm, fix_type,
                  satellites) -> bytes:
        """HIL_GPS of a GNSS record's fields (in the record's order)."""
        cm = [max(-32767, min(32767, round(v * 100.0))) for v in (vn, ve, vd)]
        speed_cm = min(65534, round(math.hypot(cm[0], cm[1])))
        cog = round(math.degrees(math.atan2(cm[1], cm[0])) * 100.0) % 36000
        return self._gps.pack(t_us, lat_e7, lon_e7, alt_mm, eph_cm, epv_cm, speed_cm, cm[0],
                              cm[1], cm[2], cog, fix_type, satellites, 0, 0)

    def _state_frame(self, att, nav, t_us) -> bytes:
        q, rates, sf = (1.0, 0.0, 0.0, 0.0), (0.0,) * 3, (0.0, 0.0, -_G0)
        if att is not None:
            q = att["q_wxyz"].tolist()
            rates = att["rates_frd_rad_s"].tolist()
            sf = att["specific_force_frd_m_s2"].tolist()
        pos, vel = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if nav is not None:
            pos = nav["pos_ned_m"].tolist()
            vel = nav["vel_ned_m_s"].tolist()
        return self.state_frame(t_us, q, rates, sf, pos, vel)

    def state_frame(self, t_us, q, rates, sf, pos, vel) -> bytes:
        """HIL_STATE_QUATERNION of GT_ATT's q, rates, specific force and GT_NAV's position
        and velocity (sequences in the records' units)."""
        lat0, lon0, alt0 = self.origin
        lat = lat0 + round(pos[0] / _M_PER_DEG * 1e7)
        coslat = max(1e-6, math.cos(math.radians(lat0 * 1e-7)))
        lon = lon0 + round(pos[1] / (_M_PER_DEG * coslat) * 1e7)
        alt = alt0 - round(pos[2] * 1000.0)
        v_cm = [max(-32767, min(32767, round(v * 100.0))) for v in vel]
        acc_mg = [max(-32767, min(32767, round(a / _G0 * 1000.0))) for a in sf]
        speed_cm = min(65535, round(math.sqrt(sum(v * v for v in v_cm))))
        return self._state.pack(t_us, q[0], q[1], q[2], q[3], rates[0], rates[1], rates[2], lat,
                                lon, alt, v_cm[0], v_cm[1], v_cm[2], speed_cm, speed_cm,
                                acc_mg[0], acc_mg[1], acc_mg[2])

    def _setpoint_frames(self, sp, t_us) -> bytes:
        c = self.codec
        roll, pitch, yaw = float(sp["roll_rad"]), float(sp["pitch_rad"]), float(sp["yaw_rad"])
        alt = float(sp["altitude_m"])
        mask = int(sp["mask"])
        t_ms = (t_us // 1000) & 0xFFFFFFFF
        att_mask = ATT_IGNORE_RATES_THRUST | (0 if mask & 1 else ATT_IGNORE_ATTITUDE)
        pos_mask = (POS_IGNORE_ALL_BUT_Z_YAW | (0 if mask & 2 else POS_IGNORE_Z)
                    | (0 if mask & 4 else POS_IGNORE_YAW))
        q = euler_to_quat(roll, pitch, yaw)
        return (c.set_attitude_target_encode(t_ms, 0, 0, att_mask, q, roll, pitch, yaw,
                                             0.0).pack(c)
                + c.set_position_target_local_ned_encode(
                    t_ms, 0, 0, MAV_FRAME_LOCAL_NED, pos_mask, 0.0, 0.0, -alt, 0.0, 0.0, 0.0,
                    0.0, 0.0, 0.0, yaw, 0.0).pack(c))


class SensorDecoder:
    """FC side: HIL messages -> records (see module docstring).

    `feed(msg, now_ns)` returns the packed records of every step the message completes
    (bytes, a whole number of 64-byte records, possibly empty)."""

    def __init__(self, origin=None, silbridge_peer: bool = True):
        self.origin = origin        # NED zero (lat_e7, lon_e7, alt_mm); None: the first truth
        self.silbridge_peer = silbridge_peer
        self.imu_hz = 0             # from the bridge's configuration; 0: take time_usec as is
        self.seq = [0] * 16
        self.last_sensor_us = -1
        self.last_state_us = -1
        self.bad = 0
        self._imu: list = []        # (t_ns, ax, ay, az, gx, gy, gz, temp)
        self._baro = None
        self._mag = None
        self._gnss = None
        self._att_sp = None
        self._pos_sp = None
        self._esc: list = []        # ESC_TELEMETRY_* messages of the step being rebuilt
        self._battery = None        # the step's BATTERY_STATUS (hil_battery.py)
        self._temp_c = 0.0
        self._wall = 0

    def _next(self, kind: int) -> int:
        s = self.seq[kind]
        self.seq[kind] = s + 1
        return s & 0xFFFFFFFF

    def feed(self, msg, now_ns: int) -> bytes:
        mid = msg.get_msgId()
        if mid == _ID_HIL_SENSOR:
            self._sensor(msg, now_ns)
            return b"" if self.silbridge_peer else self._close_step(msg.time_usec * 1000, None)
        if mid == _ID_HIL_STATE_QUATERNION:
            return self._state(msg, now_ns)
        if mid == _ID_HIL_GPS:
            self._gnss = msg
        elif mid == _ID_SET_ATTITUDE_TARGET:
            self._att_sp = msg
        elif mid == _ID_SET_POSITION_TARGET_LOCAL_NED:
            self._pos_sp = msg
        elif mid in _ID_ESC_FIRST:
            self._esc.append(msg)
        elif mid == hil_battery.ID_BATTERY_STATUS:
            self._battery = msg
        return b""

    def _reject(self, why: str):
        self.bad += 1
        raise HilInputError(why)

    def _sensor(self, m, now_ns: int) -> None:
        t_us = m.time_usec
        if t_us < self.last_sensor_us:
            self._reject(f"HIL_SENSOR time went back from {self.last_sensor_us} us to {t_us} us")
        bits = m.fields_updated
        vals = []
        if bits & UPD_IMU:
            vals += [m.xacc, m.yacc, m.zacc, m.xgyro, m.ygyro, m.zgyro]
        if bits & UPD_MAG:
            vals += [m.xmag, m.ymag, m.zmag]
        if bits & UPD_ABS_PRESSURE:
            vals.append(m.abs_pressure)
        if not all(math.isfinite(v) for v in vals):
            self._reject(f"HIL_SENSOR at {t_us} us carries NaN or infinity")
        self.last_sensor_us = t_us
        self._wall = (wall_from_fields(m.diff_pressure, m.pressure_alt, now_ns)
                      if self.silbridge_peer else now_ns)
        if not bits & UPD_ABS_PRESSURE:
            self._temp_c = m.temperature     # the IMU die temperature rides alone
        if bits & UPD_IMU:
            self._imu.append((t_us * 1000, m.xacc, m.yacc, m.zacc, m.xgyro, m.ygyro, m.zgyro,
                              self._temp_c))
        if bits & UPD_MAG:
            self._mag = (m.xmag, m.ymag, m.zmag)
        if bits & UPD_ABS_PRESSURE:
            self._baro = (f32(m.abs_pressure * 100.0), m.temperature)

    def _state(self, m, now_ns: int) -> bytes:
        t_us = m.time_usec
        if t_us < self.last_state_us:
            self._reject(f"HIL_STATE_QUATERNION time went back from {self.last_state_us} us "
                         f"to {t_us} us")
        vals = list(m.attitude_quaternion) + [m.rollspeed, m.pitchspeed, m.yawspeed]
        if not all(math.isfinite(v) for v in vals):
            self._reject(f"HIL_STATE_QUATERNION at {t_us} us carries NaN or infinity")
        self.last_state_us = t_us
        if not self.silbridge_peer:
            self._wall = now_ns
            return self._close_step(t_us * 1000, m, end=False)
        return self._close_step(t_us * 1000, m)

    def _close_step(self, step_ns: int, state, end: bool = True) -> bytes:
        wall = self._wall
        out = []
        n = len(self._imu)
        imu_hz = self.imu_hz
        m0 = (step_ns * imu_hz) // _NS - n + 1 if imu_hz else 0
        for j, (t_ns, ax, ay, az, gx, gy, gz, temp) in enumerate(self._imu):
            if imu_hz:
                # time_usec holds whole microseconds; the bridge's sample times are
                # (m * 1e9) // imu_hz ns (sim step k ends at sample m = k dt imu_hz): rebuild
                # the exact ns when the microseconds agree (any rate, e.g. 32 kHz = 31.25 us).
                t_exact = ((m0 + j) * _NS) // imu_hz
                if t_exact // 1000 == t_ns // 1000:
                    t_ns = t_exact
            out.append(_S_IMU.pack(KIND_IMU, 0, self._next(KIND_IMU), t_ns, wall, ax, ay, az,
                                   gx, gy, gz, temp, j, n, 0))
        self._imu = []
        if state is not None:
            out.extend(self._gt(state, step_ns, wall))
        if self._baro is not None:
            out.append(_S_BARO.pack(KIND_BARO, 0, self._next(KIND_BARO), step_ns, wall,
                                    *self._baro))
            self._baro = None
        if self._mag is not None:
            out.append(_S_MAG.pack(KIND_MAG, 0, self._next(KIND_MAG), step_ns, wall, *self._mag))
            self._mag = None
        if self._gnss is not None:
            out.append(self._gnss_record(self._gnss, step_ns, wall))
            self._gnss = None
        if self._att_sp is not None or self._pos_sp is not None:
            out.append(self._setpoint_record(step_ns, wall))
        if self._battery is not None:
            out.append(hil_battery.battery_record(self._battery, self._next(KIND_BATTERY),
                                                  step_ns, wall))
            self._battery = None
        if self._esc:
            out.extend(self._esc_records(step_ns, wall))
            self._esc = []
        if not out:
            return b""
        if end:
            last = bytearray(out[-1])
            last[FLAGS_OFFSET] |= FLAG_STEP_END      # the u16's low byte (little-endian)
            out[-1] = bytes(last)
        return b"".join(out)

    def _gt(self, m, step_ns: int, wall: int) -> list:
        if self.origin is None:     # a simulator that sent no GPS_GLOBAL_ORIGIN: start = zero
            self.origin = (m.lat, m.lon, m.alt)
        lat0, lon0, alt0 = self.origin
        coslat = max(1e-6, math.cos(math.radians(lat0 * 1e-7)))
        pn = (m.lat - lat0) * 1e-7 * _M_PER_DEG
        pe = (m.lon - lon0) * 1e-7 * _M_PER_DEG * coslat
        pd = (alt0 - m.alt) / 1000.0
        sf = [a * _G0 / 1000.0 for a in (m.xacc, m.yacc, m.zacc)]
        q = m.attitude_quaternion
        return [_S_GT_ATT.pack(KIND_GT_ATT, 0, self._next(KIND_GT_ATT), step_ns, wall, q[0], q[1],
                               q[2], q[3], m.rollspeed, m.pitchspeed, m.yawspeed, *sf),
                _S_GT_NAV.pack(KIND_GT_NAV, 0, self._next(KIND_GT_NAV), step_ns, wall, pn, pe, pd,
                               m.vx / 100.0, m.vy / 100.0, m.vz / 100.0, 0)]

    def _gnss_record(self, g, step_ns: int, wall: int) -> bytes:
        return _S_GNSS.pack(KIND_GNSS, 0, self._next(KIND_GNSS), step_ns, wall, g.lat, g.lon, g.alt,
                            g.vn / 100.0, g.ve / 100.0, g.vd / 100.0, g.eph, g.epv, g.fix_type,
                            g.satellites_visible)

    def _esc_records(self, step_ns: int, wall: int) -> list:
        """The ESC records of the step's ESC_TELEMETRY_* messages, motors in order (a slot
        with count 0 did not report)."""
        slots = []
        for m in self._esc:
            first = _ID_ESC_FIRST[m.get_msgId()]
            for j in range(4):
                if m.count[j]:
                    slots.append((first + j, m))
        slots.sort(key=lambda s: s[0])
        out = []
        for motor, m in slots:
            j = motor % 4
            out.append(_S_ESC.pack(KIND_ESC, 0, self._next(KIND_ESC), step_ns, wall, motor,
                                   len(slots), 0, float(m.rpm[j]), m.voltage[j] / 100.0,
                                   m.current[j] / 100.0, float(m.temperature[j]),
                                   float(m.totalcurrent[j])))
        return out

    def _setpoint_record(self, step_ns: int, wall: int) -> bytes:
        a, p = self._att_sp, self._pos_sp
        self._att_sp = self._pos_sp = None
        roll = pitch = yaw = 0.0
        alt = float("nan")
        mask = 0
        if a is not None:
            roll, pitch, yaw = a.body_roll_rate, a.body_pitch_rate, a.body_yaw_rate
            if not a.type_mask & ATT_IGNORE_ATTITUDE:
                mask |= 1
        if p is not None:
            alt = -p.z
            if not p.type_mask & POS_IGNORE_Z:
                mask |= 2
            if not p.type_mask & POS_IGNORE_YAW:
                mask |= 4
                yaw = p.yaw
        return _S_SETPOINT.pack(KIND_SETPOINT, 0, self._next(KIND_SETPOINT), step_ns, wall, roll,
                                pitch, yaw, alt, mask)
