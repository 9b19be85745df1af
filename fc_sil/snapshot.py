"""build_snapshot(vehicle): the VehicleSnapshot the GCS server's telemetry reads.

Built once per outer-loop step on the vehicle thread and published with one reference swap
(mavlink/gcs/vehicle_api.py). Everything comes from the FC's own view: the C core's status row
(attitude, rates, PID terms, PWM, altitude), the position estimator, the GNSS receiver's last
fix, the battery model, the pilot input, the mode and failsafe state.

Conventions as ArduCopter fills its messages: PID_TUNING attitude rows in deg/s with the PID
terms as normalised outputs (our terms are in microseconds about the mixer centre; 500 us is
a full normalised unit, the IMAX convention of fc_params.def); the accel-z row (axis 4)
carries the vertical channel we have: desired and achieved climb rate (m/s) with the altitude
loop's throttle above hover as P. SYS_STATUS health: a sensor is healthy while its stream is
fresh; PREARM_CHECK healthy when armed or when the pre-arm checks pass.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import (CopterMode, EscRow, NavControllerOutput,
                                           PidTuningRow, SensorBit, VehicleSnapshot)
from silbridge.shm.records import Kind

from .prearm import prearm_failure

US_PER_NORM = 500.0
_G = 9.80665
_P0_PA = 101325.0


def _sensor_bits(v) -> tuple[int, int, int]:
    to_ns = int(v.cfg.sens_timeout_s * 1e9)
    seen = v.last_seen_ns

    def fresh(kind) -> bool:
        return seen[kind] >= 0 and v.sim_ns - seen[kind] <= to_ns

    present = (SensorBit.GYRO | SensorBit.ACCEL | SensorBit.MAG | SensorBit.ABS_PRESSURE
               | SensorBit.GPS | SensorBit.ANGULAR_RATE_CONTROL
               | SensorBit.ATTITUDE_STABILIZATION | SensorBit.YAW_POSITION
               | SensorBit.Z_ALTITUDE_CONTROL | SensorBit.XY_POSITION_CONTROL
               | SensorBit.MOTOR_OUTPUTS | SensorBit.AHRS | SensorBit.BATTERY
               | SensorBit.PREARM_CHECK)
    enabled = present if v.armed else present & ~(
        SensorBit.ANGULAR_RATE_CONTROL | SensorBit.ATTITUDE_STABILIZATION
        | SensorBit.YAW_POSITION | SensorBit.Z_ALTITUDE_CONTROL | SensorBit.XY_POSITION_CONTROL
        | SensorBit.MOTOR_OUTPUTS)
    if not v.cfg.compass_use:
        enabled &= ~SensorBit.MAG
    health = present
    imu_ok = fresh(Kind.IMU) and not v.rejected_recently
    if not imu_ok:
        health &= ~(SensorBit.GYRO | SensorBit.ACCEL | SensorBit.AHRS
                    | SensorBit.ANGULAR_RATE_CONTROL | SensorBit.ATTITUDE_STABILIZATION)
    if not fresh(Kind.BARO):
        health &= ~(SensorBit.ABS_PRESSURE | SensorBit.Z_ALTITUDE_CONTROL)
    if not fresh(Kind.MAG):
        health &= ~(SensorBit.MAG | SensorBit.YAW_POSITION)
    if not v.position_ok():
        health &= ~(SensorBit.GPS | SensorBit.XY_POSITION_CONTROL)
    if v.failsafe.batt_low or v.failsafe.batt_crit:
        health &= ~SensorBit.BATTERY
    if v.imu_run_s < 1.0 or v.trust < 0.5:
        health &= ~SensorBit.AHRS
    if not v.armed and prearm_failure(v) is not None:
        health &= ~SensorBit.PREARM_CHECK
    f_present, f_enabled, f_healthy = v.fence.sys_status(v)
    if f_present:
        present |= SensorBit.GEOFENCE
    if f_enabled:
        enabled |= SensorBit.GEOFENCE
    if f_healthy:       # ArduCopter: healthy unless present and breached (absent: healthy)
        health |= SensorBit.GEOFENCE
    return present, enabled, health


def _ekf_fields(v) -> dict:
    """EKF_STATUS_REPORT: flags and test ratios as EKF3 reports them (innov_ratios.py)."""
    return v.failsafe.ratios.status_fields(v)


def _pid_rows(v, st) -> tuple[PidTuningRow, ...]:
    rows = []
    tgt, rate = st["rate_target_frd_rad_s"], st["rate_frd_rad_s"]
    for axis in range(3):
        rows.append(PidTuningRow(
            axis + 1, math.degrees(float(tgt[axis])), math.degrees(float(rate[axis])),
            float(st["pid_ff"][axis]) / US_PER_NORM, float(st["pid_p"][axis]) / US_PER_NORM,
            float(st["pid_i"][axis]) / US_PER_NORM, float(st["pid_d"][axis]) / US_PER_NORM))
    rows.append(PidTuningRow(4, float(st["climb_target_m_s"]), float(st["climb_est_m_s"]),
                             v.cfg.hover_throttle, float(st["throttle"]) - v.cfg.hover_throttle,
                             0.0, 0.0))
    return tuple(rows)


def _system_status(v) -> int:
    if v.failsafe.active:
        return mav.MAV_STATE_CRITICAL
    if v.imu_run_s < 1.0:
        return mav.MAV_STATE_BOOT
    return mav.MAV_STATE_ACTIVE if v.armed else mav.MAV_STATE_STANDBY


def _landed_state(v) -> int:
    if v.armed and v.takeoff_in_progress:
        return mav.MAV_LANDED_STATE_TAKEOFF
    if not v.airborne:
        return mav.MAV_LANDED_STATE_ON_GROUND
    if v.landing:
        return mav.MAV_LANDED_STATE_LANDING
    return mav.MAV_LANDED_STATE_IN_AIR


def build_snapshot(v) -> VehicleSnapshot:
    st = v.status
    # before the first core status: nothing present, and the geofence "healthy" as ArduCopter
    # reports an absent fence (MAVProxy says "fence breach" when that bit goes from 1 to 0)
    present, enabled, health = _sensor_bits(v) if st is not None else (0, 0, SensorBit.GEOFENCE)
    est = v.est
    lat_e7, lon_e7 = est.latlon_e7()
    alt_msl_m = v.alt_datum_msl_m + v.alt_m
    # the vertical channel's zero and home above the estimator origin (NED z = -up)
    datum_up = v.alt_datum_msl_m - est.origin.alt_msl_m if est.origin is not None else 0.0
    home_up = datum_up + v.home_up_m
    vn, ve = est.vel_ne_m_s
    vd = -v.climb_m_s
    g = v.gnss
    gps = {}
    if g is not None:
        gvn, gve = g["vel_ned_m_s"][0], g["vel_ned_m_s"][1]
        gspd = math.hypot(gvn, gve)
        # AP_GPS says NO_GPS (0) once its receiver has been silent GPS_TIMEOUT_MS (4 s)
        fix_type = int(g["fix_type"]) if v.sim_ns - g["sim_ns"] <= 4_000_000_000 else 0
        gps = dict(gps_fix_type=fix_type, gps_sats=int(g["satellites"]),
                   gps_lat_e7=int(g["lat_e7"]), gps_lon_e7=int(g["lon_e7"]),
                   gps_alt_msl_mm=int(g["alt_mm"]), gps_vel_cm_s=int(gspd * 100.0),
                   gps_cog_cdeg=(int(math.degrees(math.atan2(gve, gvn)) * 100.0) % 36000
                                 if gspd > 0.2 else 65535))
    b = v.battery
    ch = v.pilot.channels_us
    if st is not None:
        rates = st["rate_frd_rad_s"]
        servo = tuple(int(x) for x in st["pwm_us"])
        thr_pct = int(round(100.0 * float(st["throttle"]))) if v.armed else 0
        pid_rows = _pid_rows(v, st)
    else:
        rates, servo, thr_pct, pid_rows = (0.0, 0.0, 0.0), (), 0, ()
    vibe = v.core.vibration()      # per IMU sample in C (fc_sil/core/fc_vibe.h)
    wp = v.wp
    nav_bearing = int(math.degrees(wp.bearing_rad)) % 360 if wp.bearing_rad is not None else 0
    press_hpa = _P0_PA * max(0.0, 1.0 - alt_msl_m / 44330.0) ** 5.255 / 100.0
    return VehicleSnapshot(
        time_boot_ms=v.sim_ns // 1_000_000,
        armed=v.armed, custom_mode=v.mode.number,
        guided_enabled=bool(v.armed and v.mode.guided_enabled),
        system_status=_system_status(v), landed_state=_landed_state(v),
        sensors_present=present, sensors_enabled=enabled, sensors_health=health,
        load_permille=int(min(1000, v.load_permille())),
        roll_rad=v.euler_rad[0], pitch_rad=v.euler_rad[1], yaw_rad=v.euler_rad[2],
        rollspeed_rad_s=float(rates[0]), pitchspeed_rad_s=float(rates[1]),
        yawspeed_rad_s=float(rates[2]), q_wxyz=v.q_wxyz,
        lat_e7=lat_e7, lon_e7=lon_e7, alt_msl_mm=int(alt_msl_m * 1000.0),
        alt_rel_mm=int((v.alt_m - v.home_up_m) * 1000.0), vel_ned_m_s=(vn, ve, vd),
        pos_ned_m=(est.pos_ne_m[0], est.pos_ne_m[1], -(v.alt_m + datum_up)),
        home_set=v.home_set, home_lat_e7=v.home_lat_e7, home_lon_e7=v.home_lon_e7,
        home_alt_msl_mm=int(v.home_alt_msl_m * 1000.0), home_epoch=v.home_epoch,
        home_ned_m=(v.home_ne[0], v.home_ne[1], -home_up),
        battery_voltage_v=b.voltage_v, battery_current_a=b.current_a,
        battery_remaining_pct=b.remaining_pct, battery_consumed_mah=b.consumed_mah,
        servo_us=servo, rc_channels_us=tuple(ch),
        rc_rssi=255 if v.pilot.t_s is None else 254,
        accel_frd_m_s2=tuple(v.accel_frd), gyro_frd_rad_s=tuple(float(r) for r in rates),
        baro_press_hpa=press_hpa,
        groundspeed_m_s=math.hypot(vn, ve), airspeed_m_s=math.hypot(vn, ve),
        throttle_pct=thr_pct, climb_m_s=v.climb_m_s,
        nav=_nav_output(v, nav_bearing), pid_rows=pid_rows,
        mission_seq=v.mission.current, mission_state=v.mission.state,
        mission_mode=1 if v.mode.number == CopterMode.AUTO else 0,
        vibration_m_s2=vibe[:3], clipping=(int(vibe[3]), 0, 0), esc=_esc_rows(v),
        flight_custom_version=v.custom_version, **gps, **_ekf_fields(v),
        **v.fence.status_fields(v))


def _esc_rows(v) -> tuple:
    """The ESCs' latest telemetry as the core holds it (fc_sil/core/fc_esc.h)."""
    return tuple(EscRow(r.motor, r.temperature_c, r.voltage_v, r.current_a, r.consumption_mah,
                        r.rpm, r.count) for r in v.core.esc_reports())


def _nav_output(v, bearing_deg: int):
    d = v.wp.distance_to_dest(v.est.pos_ne_m) if v.wp.active else 0.0
    return NavControllerOutput(
        nav_roll_deg=math.degrees(v.cmd_roll), nav_pitch_deg=math.degrees(v.cmd_pitch),
        nav_bearing_deg=bearing_deg, target_bearing_deg=bearing_deg,
        wp_dist_m=int(min(65535, d)), alt_error_m=v.alt_target_m - v.alt_m,
        xtrack_error_m=v.pos_ctl.pos_error_m)
