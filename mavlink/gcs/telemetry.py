"""Telemetry messages built from a VehicleSnapshot (pure functions, no I/O).

Each encoder turns one snapshot into the MAVLink message(s) ArduCopter would send, with the
same units and conventions (GLOBAL_POSITION_INT heading in centidegrees 0..35999, SYS_STATUS
battery in mV/cA, RAW_IMU in mG/mrad/s/mGauss as ArduPilot fills it, and so on). Integer
fields are clamped to their wire type so an odd snapshot value can never make packing fail.

``ENCODERS`` maps message id -> encoder; ``TelemetryContext`` carries the few things that are
not vehicle state (mission total, GCS_PID_MASK, link statistics, Unix time).

Every time stamp is the vehicle's simulated time, as ArduCopter SITL stamps them: time_boot_ms
and time_usec from the snapshot, and SYSTEM_TIME's Unix time advancing with sim time (at
--speedup 5 ArduCopter's time_unix_usec gains 5 s per wall second, like its GPS time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import VehicleSnapshot

# AUTOPILOT_VERSION.capabilities: what this server actually implements.
CAPABILITIES = (mav.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
                | mav.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
                | mav.MAV_PROTOCOL_CAPABILITY_MISSION_INT
                | mav.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | mav.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET
                | mav.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
                | mav.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
                | mav.MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | mav.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
                | mav.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY)

# ArduPilot's USB vendor / product id pair for SITL builds is 0/0; keep it.
BASE_MODE_FIXED = (mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mav.MAV_MODE_FLAG_STABILIZE_ENABLED
                   | mav.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED)
_G_M_S2 = 9.80665


@dataclass(slots=True)
class TelemetryContext:
    mission_total: int = 0          # items excluding home
    pid_mask: int = 0               # GCS_PID_MASK
    drop_rate_comm_cpct: int = 0    # c% of received frames dropped
    errors_comm: int = 0
    unix_us: int = 0                # Unix time of the snapshot's sim time (SYSTEM_TIME)


def _clamp(v, lo: int, hi: int) -> int:
    try:
        iv = int(v)
    except (ValueError, OverflowError, TypeError):
        return 0
    return lo if iv < lo else hi if iv > hi else iv


def u8(v): return _clamp(v, 0, 0xFF)
def u16(v): return _clamp(v, 0, 0xFFFF)
def i8(v): return _clamp(v, -0x80, 0x7F)
def i16(v): return _clamp(v, -0x8000, 0x7FFF)
def u32(v): return _clamp(v, 0, 0xFFFFFFFF)
def i32(v): return _clamp(v, -0x80000000, 0x7FFFFFFF)


def _rnd(v: float) -> float:
    return v if math.isfinite(v) else 0.0


def _yaw_cdeg(yaw_rad: float) -> int:
    return int(round(math.degrees(_rnd(yaw_rad)) * 100.0)) % 36000


def heartbeat(s: VehicleSnapshot, ctx: TelemetryContext):
    base = BASE_MODE_FIXED
    if s.guided_enabled:
        base |= mav.MAV_MODE_FLAG_GUIDED_ENABLED
    if s.armed:
        base |= mav.MAV_MODE_FLAG_SAFETY_ARMED
    return [mav.MAVLink_heartbeat_message(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                          base, u32(s.custom_mode), u8(s.system_status), 3)]


def sys_status(s: VehicleSnapshot, ctx: TelemetryContext):
    current_ca = -1 if s.battery_current_a < 0 else i16(s.battery_current_a * 100.0)
    return [mav.MAVLink_sys_status_message(
        u32(s.sensors_present), u32(s.sensors_enabled), u32(s.sensors_health),
        u16(s.load_permille), u16(s.battery_voltage_v * 1000.0), current_ca,
        i8(s.battery_remaining_pct), u16(ctx.drop_rate_comm_cpct), u16(ctx.errors_comm),
        0, 0, 0, 0)]


def system_time(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_system_time_message(max(0, int(ctx.unix_us)), u32(s.time_boot_ms))]


def gps_raw_int(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_gps_raw_int_message(
        s.time_boot_ms * 1000, u8(s.gps_fix_type), i32(s.gps_lat_e7), i32(s.gps_lon_e7),
        i32(s.gps_alt_msl_mm), u16(s.gps_eph_cm), u16(s.gps_epv_cm), u16(s.gps_vel_cm_s),
        u16(s.gps_cog_cdeg), u8(s.gps_sats))]


def _imu_milli(s: VehicleSnapshot):
    acc = [i16(a / _G_M_S2 * 1000.0) for a in s.accel_frd_m_s2]
    gyr = [i16(g * 1000.0) for g in s.gyro_frd_rad_s]
    mag = [i16(m * 1000.0) for m in s.mag_frd_gauss]
    return acc, gyr, mag


def scaled_imu(s: VehicleSnapshot, ctx: TelemetryContext):
    acc, gyr, mag = _imu_milli(s)
    return [mav.MAVLink_scaled_imu_message(u32(s.time_boot_ms), *acc, *gyr, *mag,
                                           i16(s.imu_temperature_degc * 100.0))]


def raw_imu(s: VehicleSnapshot, ctx: TelemetryContext):
    acc, gyr, mag = _imu_milli(s)
    return [mav.MAVLink_raw_imu_message(s.time_boot_ms * 1000, *acc, *gyr, *mag, 0,
                                        i16(s.imu_temperature_degc * 100.0))]


def highres_imu(s: VehicleSnapshot, ctx: TelemetryContext):
    a, g, m = s.accel_frd_m_s2, s.gyro_frd_rad_s, s.mag_frd_gauss
    pressure_alt_m = 44330.0 * (1.0 - (max(s.baro_press_hpa, 1e-3) / 1013.25) ** 0.190295)
    return [mav.MAVLink_highres_imu_message(
        s.time_boot_ms * 1000, *map(_rnd, a), *map(_rnd, g), *map(_rnd, m),
        _rnd(s.baro_press_hpa), 0.0, _rnd(pressure_alt_m), _rnd(s.imu_temperature_degc),
        0x1FFF, 0)]


def scaled_pressure(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_scaled_pressure_message(u32(s.time_boot_ms), _rnd(s.baro_press_hpa), 0.0,
                                                i16(s.baro_temp_degc * 100.0))]


def attitude(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_attitude_message(u32(s.time_boot_ms), _rnd(s.roll_rad), _rnd(s.pitch_rad),
                                         _rnd(s.yaw_rad), _rnd(s.rollspeed_rad_s),
                                         _rnd(s.pitchspeed_rad_s), _rnd(s.yawspeed_rad_s))]


def attitude_quaternion(s: VehicleSnapshot, ctx: TelemetryContext):
    q = [_rnd(v) for v in s.q_wxyz]
    return [mav.MAVLink_attitude_quaternion_message(
        u32(s.time_boot_ms), *q, _rnd(s.rollspeed_rad_s), _rnd(s.pitchspeed_rad_s),
        _rnd(s.yawspeed_rad_s), (0.0, 0.0, 0.0, 0.0))]


def local_position_ned(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_local_position_ned_message(u32(s.time_boot_ms),
                                                   *map(_rnd, s.pos_ned_m),
                                                   *map(_rnd, s.vel_ned_m_s))]


def global_position_int(s: VehicleSnapshot, ctx: TelemetryContext):
    v = [i16(_rnd(x) * 100.0) for x in s.vel_ned_m_s]
    return [mav.MAVLink_global_position_int_message(
        u32(s.time_boot_ms), i32(s.lat_e7), i32(s.lon_e7), i32(s.alt_msl_mm),
        i32(s.alt_rel_mm), *v, _yaw_cdeg(s.yaw_rad))]


def servo_output_raw(s: VehicleSnapshot, ctx: TelemetryContext):
    servos = [u16(v) for v in s.servo_us[:16]] + [0] * (16 - min(16, len(s.servo_us)))
    # time_usec is a uint32 here: it wraps after 71.6 min, as ArduPilot's micros() does
    return [mav.MAVLink_servo_output_raw_message((s.time_boot_ms * 1000) & 0xFFFFFFFF, 0,
                                                 *servos)]


def rc_channels(s: VehicleSnapshot, ctx: TelemetryContext):
    chans = [u16(v) for v in s.rc_channels_us[:18]]
    count = len(chans)
    chans += [65535] * (18 - count)          # UINT16_MAX: channel unused
    return [mav.MAVLink_rc_channels_message(u32(s.time_boot_ms), count, *chans, u8(s.rc_rssi))]


def mission_current(s: VehicleSnapshot, ctx: TelemetryContext):
    state = s.mission_state if ctx.mission_total > 0 else mav.MISSION_STATE_NO_MISSION
    return [mav.MAVLink_mission_current_message(u16(s.mission_seq), u16(ctx.mission_total),
                                                u8(state), u8(s.mission_mode))]


def nav_controller_output(s: VehicleSnapshot, ctx: TelemetryContext):
    n = s.nav
    return [mav.MAVLink_nav_controller_output_message(
        _rnd(n.nav_roll_deg), _rnd(n.nav_pitch_deg), i16(n.nav_bearing_deg),
        i16(n.target_bearing_deg), u16(n.wp_dist_m), _rnd(n.alt_error_m),
        _rnd(n.aspd_error_m_s), _rnd(n.xtrack_error_m))]


def vfr_hud(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_vfr_hud_message(
        _rnd(s.airspeed_m_s), _rnd(s.groundspeed_m_s), i16(_yaw_cdeg(s.yaw_rad) // 100),
        u16(s.throttle_pct), s.alt_msl_mm / 1000.0, _rnd(s.climb_m_s))]


def battery_status(s: VehicleSnapshot, ctx: TelemetryContext):
    cells = [u16(s.battery_voltage_v * 1000.0)] + [65535] * 9   # total voltage in cell 0
    current_ca = -1 if s.battery_current_a < 0 else i16(s.battery_current_a * 100.0)
    consumed = -1 if s.battery_consumed_mah < 0 else i32(s.battery_consumed_mah)
    return [mav.MAVLink_battery_status_message(
        0, mav.MAV_BATTERY_FUNCTION_UNKNOWN, mav.MAV_BATTERY_TYPE_LIPO, 32767, cells,
        current_ca, consumed, -1, i8(s.battery_remaining_pct))]


def pid_tuning(s: VehicleSnapshot, ctx: TelemetryContext):
    out = []
    for row in s.pid_rows:
        if 1 <= row.axis <= 32 and ctx.pid_mask & (1 << (row.axis - 1)):
            out.append(mav.MAVLink_pid_tuning_message(
                u8(row.axis), _rnd(row.desired), _rnd(row.achieved), _rnd(row.ff), _rnd(row.p),
                _rnd(row.i), _rnd(row.d), _rnd(row.srate), _rnd(row.pdmod)))
    return out


def vibration(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_vibration_message(s.time_boot_ms * 1000, *map(_rnd, s.vibration_m_s2),
                                          *(u32(c) for c in s.clipping))]


# ESC_TELEMETRY frames by first motor, four ESCs a frame (ArduPilot sends up to 32 this way).
_ESC_TELEMETRY = {0: mav.MAVLink_esc_telemetry_1_to_4_message,
                  4: mav.MAVLink_esc_telemetry_5_to_8_message}


def esc_telemetry(s: VehicleSnapshot, ctx: TelemetryContext):
    """ArduPilot's MSG_ESC_TELEMETRY as AP_ESC_Telem fills it: per group of four ESCs with
    data, temperature degC, voltage cV, current cA, consumption mAh, rpm, reports received,
    every u16 clamped to 0..65535 (slots of silent ESCs zero); nothing while no ESC reports."""
    groups: dict[int, list] = {}
    for r in s.esc:
        first = r.motor // 4 * 4
        if first not in _ESC_TELEMETRY:
            continue
        f = groups.setdefault(first, [[0] * 4 for _ in range(6)])
        j = r.motor - first
        f[0][j] = u8(round(r.temperature_c))
        f[1][j] = u16(round(r.voltage_v * 100.0))
        f[2][j] = u16(round(r.current_a * 100.0))
        f[3][j] = u16(round(r.consumption_mah))
        f[4][j] = u16(round(r.rpm))
        f[5][j] = r.count & 0xFFFF
    return [_ESC_TELEMETRY[first](*f) for first, f in sorted(groups.items())]


def extended_sys_state(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_extended_sys_state_message(mav.MAV_VTOL_STATE_UNDEFINED,
                                                   u8(s.landed_state))]


def home_position(s: VehicleSnapshot, ctx: TelemetryContext):
    # As ArduCopter 4.6 fills it: x, y, z = home about the EKF origin (NED, m), q unknown (NaN),
    # time_usec = time since boot.
    if not s.home_set:
        return []
    nan = float("nan")
    return [mav.MAVLink_home_position_message(
        i32(s.home_lat_e7), i32(s.home_lon_e7), i32(s.home_alt_msl_mm), *map(_rnd, s.home_ned_m),
        (nan, nan, nan, nan), 0.0, 0.0, 0.0, s.time_boot_ms * 1000)]


def ekf_status_report(s: VehicleSnapshot, ctx: TelemetryContext):
    return [mav.MAVLink_ekf_status_report_message(
        u16(s.ekf_flags), _rnd(s.ekf_vel_var), _rnd(s.ekf_pos_h_var), _rnd(s.ekf_pos_v_var),
        _rnd(s.ekf_compass_var), 0.0, 0.0)]


def fence_status(s: VehicleSnapshot, ctx: TelemetryContext):
    if not s.fence_enabled:
        return []
    return [mav.MAVLink_fence_status_message(
        u8(s.fence_breach_status), u16(s.fence_breach_count), u8(s.fence_breach_type),
        u32(s.fence_breach_time_ms), u8(s.fence_mitigation))]


def autopilot_version(s: VehicleSnapshot, ctx: TelemetryContext):
    custom = s.flight_custom_version.encode("ascii", "replace")[:8].ljust(8, b"\0")
    return [mav.MAVLink_autopilot_version_message(
        CAPABILITIES, u32(s.flight_sw_version), 0, 0, u32(s.board_version), list(custom),
        [0] * 8, [0] * 8, 0, 0, s.uid & 0xFFFFFFFFFFFFFFFF)]


Encoder = Callable[[VehicleSnapshot, TelemetryContext], list]

ENCODERS: dict[int, Encoder] = {
    mav.MAVLINK_MSG_ID_HEARTBEAT: heartbeat,
    mav.MAVLINK_MSG_ID_SYS_STATUS: sys_status,
    mav.MAVLINK_MSG_ID_SYSTEM_TIME: system_time,
    mav.MAVLINK_MSG_ID_GPS_RAW_INT: gps_raw_int,
    mav.MAVLINK_MSG_ID_SCALED_IMU: scaled_imu,
    mav.MAVLINK_MSG_ID_RAW_IMU: raw_imu,
    mav.MAVLINK_MSG_ID_HIGHRES_IMU: highres_imu,
    mav.MAVLINK_MSG_ID_SCALED_PRESSURE: scaled_pressure,
    mav.MAVLINK_MSG_ID_ATTITUDE: attitude,
    mav.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: attitude_quaternion,
    mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED: local_position_ned,
    mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: global_position_int,
    mav.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW: servo_output_raw,
    mav.MAVLINK_MSG_ID_RC_CHANNELS: rc_channels,
    mav.MAVLINK_MSG_ID_MISSION_CURRENT: mission_current,
    mav.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: nav_controller_output,
    mav.MAVLINK_MSG_ID_VFR_HUD: vfr_hud,
    mav.MAVLINK_MSG_ID_BATTERY_STATUS: battery_status,
    mav.MAVLINK_MSG_ID_PID_TUNING: pid_tuning,
    mav.MAVLINK_MSG_ID_VIBRATION: vibration,
    mav.MAVLINK_MSG_ID_ESC_TELEMETRY_1_TO_4: esc_telemetry,
    mav.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: extended_sys_state,
    mav.MAVLINK_MSG_ID_HOME_POSITION: home_position,
    mav.MAVLINK_MSG_ID_EKF_STATUS_REPORT: ekf_status_report,
    mav.MAVLINK_MSG_ID_FENCE_STATUS: fence_status,
    mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION: autopilot_version,
}


def statustext_messages(severity: int, text: str, chunk_id: int) -> list:
    """STATUSTEXT, split into 50-byte chunks (MAVLink 2 id/chunk_seq) when longer."""
    data = text.encode("ascii", "replace")
    if len(data) <= 50:
        return [mav.MAVLink_statustext_message(u8(severity), data)]
    chunks = [data[i:i + 50] for i in range(0, len(data), 50)]
    if len(data) % 50 == 0:
        chunks.append(b"")      # the spec's terminator when the text fills the last chunk
    return [mav.MAVLink_statustext_message(u8(severity), c, chunk_id, n)
            for n, c in enumerate(chunks)]
