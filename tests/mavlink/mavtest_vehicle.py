"""A small honest test vehicle for the GCS server tests.

Not the real flight controller (that lives in fc_sil/): a kinematic state holder that
implements ``VehicleCommands`` and ``ParamStore`` the way the real one is expected to, and runs
its own "outer loop" thread at 100 Hz that services the server's command queue and publishes
snapshots, exactly as fc_sil's loop will. Arming succeeds only when ``prearm_ok`` is set (or
when forced); takeoff needs GUIDED, armed and landed; climb and descent are integrated at
fixed speeds, so tests see altitude, landed state and mission progress change.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import (CopterMode, PidTuningRow, SensorBit, VehicleSnapshot)

T = mav  # short alias for MAV_PARAM_TYPE_*


@dataclass
class ParamDecl:
    name: str
    ptype: int
    default: float
    lo: float
    hi: float


DECLS = [
    ParamDecl("SYSID_THISMAV", T.MAV_PARAM_TYPE_INT16, 1, 1, 255),
    ParamDecl("SYSID_MYGCS", T.MAV_PARAM_TYPE_INT16, 255, 1, 255),
    ParamDecl("FRAME_CLASS", T.MAV_PARAM_TYPE_INT8, 1, 0, 15),
    ParamDecl("GCS_PID_MASK", T.MAV_PARAM_TYPE_INT16, 0, 0, 15),
    ParamDecl("ATC_RAT_RLL_P", T.MAV_PARAM_TYPE_REAL32, 0.135, 0.0, 0.5),
    ParamDecl("ATC_RAT_RLL_I", T.MAV_PARAM_TYPE_REAL32, 0.135, 0.0, 2.0),
    ParamDecl("ATC_RAT_RLL_D", T.MAV_PARAM_TYPE_REAL32, 0.0036, 0.0, 0.05),
    ParamDecl("ATC_RAT_PIT_P", T.MAV_PARAM_TYPE_REAL32, 0.135, 0.0, 0.5),
    ParamDecl("ATC_RAT_YAW_P", T.MAV_PARAM_TYPE_REAL32, 0.18, 0.0, 2.5),
    ParamDecl("ATC_ACCEL_R_MAX", T.MAV_PARAM_TYPE_REAL32, 110000.0, 0.0, 180000.0),
    ParamDecl("MOT_SPIN_ARM", T.MAV_PARAM_TYPE_REAL32, 0.10, 0.0, 0.2),
    ParamDecl("MOT_PWM_MIN", T.MAV_PARAM_TYPE_INT16, 1000, 0, 2000),
    ParamDecl("WPNAV_SPEED", T.MAV_PARAM_TYPE_REAL32, 1000.0, 10.0, 2000.0),
    ParamDecl("RTL_ALT", T.MAV_PARAM_TYPE_INT32, 1500, 200, 300000),
    ParamDecl("DISARM_DELAY", T.MAV_PARAM_TYPE_INT8, 10, 0, 127),
    ParamDecl("INS_HNTCH_ENABLE", T.MAV_PARAM_TYPE_INT8, 0, 0, 1),
    ParamDecl("ANGLE_MAX", T.MAV_PARAM_TYPE_INT16, 3000, 1000, 8000),
    ParamDecl("RALLY_TOTAL", T.MAV_PARAM_TYPE_INT8, 0, 0, 127),
    ParamDecl("SR0_POSITION", T.MAV_PARAM_TYPE_INT16, 0, 0, 50),
    ParamDecl("SR0_EXTRA1", T.MAV_PARAM_TYPE_INT16, 0, 0, 50),
]


class DeclaredParamStore:
    """ParamStore with declared types and ranges, safe to set from the GCS thread."""

    def __init__(self, decls=DECLS):
        self._decls = {d.name: d for d in decls}
        self._order = [d.name for d in decls]
        self._values = {d.name: d.default for d in decls}
        self._lock = threading.Lock()

    def names(self):
        return self._order

    def get(self, name):
        d = self._decls[name]
        with self._lock:
            return self._values[name], d.ptype

    def set(self, name, value):
        d = self._decls[name]
        if not d.lo <= value <= d.hi:
            return f"{value:g} out of range {d.lo:g}..{d.hi:g}"
        with self._lock:
            self._values[name] = value
        return None


GUIDED_TAKEOFF_MODES = {CopterMode.GUIDED}
KNOWN_MODES = {v for k, v in vars(CopterMode).items() if not k.startswith("_")}
HOME = (-353632621, 1491652374, 584_000)   # lat_e7, lon_e7, alt_msl_mm


class KinematicVehicle:
    """Implements VehicleCommands; ``run_loop(server)`` is the vehicle's outer loop."""

    CLIMB_M_S = 5.0

    def __init__(self):
        self.prearm_ok = True
        self.prearm_reason = "PreArm: Gyros not calibrated"
        self.armed = False
        self.mode = CopterMode.STABILIZE
        self.alt_m = 0.0
        self.target_alt_m = 0.0
        self.landed = True
        self.mission_items = ()
        self.mission_seq = 0
        self.calls: list[tuple[str, tuple]] = []
        self.calls_lock = threading.Lock()
        self.service_enabled = True
        self._stop = threading.Event()
        self._thread = None
        self._t0 = time.monotonic()

    # -- bookkeeping ----------------------------------------------------------------------------
    def _record(self, name, *args):
        with self.calls_lock:
            self.calls.append((name, args))

    def calls_named(self, name):
        with self.calls_lock:
            return [a for n, a in self.calls if n == name]

    # -- VehicleCommands --------------------------------------------------------------------------
    def arm(self, force):
        self._record("arm", force)
        if self.armed:
            return mav.MAV_RESULT_ACCEPTED, None
        if not self.prearm_ok and not force:
            return mav.MAV_RESULT_FAILED, self.prearm_reason
        self.armed = True
        return mav.MAV_RESULT_ACCEPTED, None

    def disarm(self, force):
        self._record("disarm", force)
        if not self.landed and not force:
            return mav.MAV_RESULT_DENIED, "Disarm: vehicle is flying"
        self.armed = False
        return mav.MAV_RESULT_ACCEPTED, None

    def set_mode(self, custom_mode):
        self._record("set_mode", custom_mode)
        if custom_mode not in KNOWN_MODES:
            return mav.MAV_RESULT_FAILED, f"Mode change to {custom_mode} failed: unknown mode"
        self.mode = custom_mode
        return mav.MAV_RESULT_ACCEPTED, None

    def takeoff(self, alt_m):
        self._record("takeoff", alt_m)
        if not self.armed:
            return mav.MAV_RESULT_FAILED, "Takeoff: not armed"
        if self.mode not in GUIDED_TAKEOFF_MODES or not self.landed:
            return mav.MAV_RESULT_FAILED, "Takeoff: needs GUIDED and landed"
        self.target_alt_m = alt_m
        self.landed = False
        return mav.MAV_RESULT_ACCEPTED, None

    def land(self):
        self._record("land")
        self.mode = CopterMode.LAND
        self.target_alt_m = 0.0
        return mav.MAV_RESULT_ACCEPTED, None

    def rtl(self):
        self._record("rtl")
        self.mode = CopterMode.RTL
        self.target_alt_m = 0.0
        return mav.MAV_RESULT_ACCEPTED, None

    def mission_start(self, first, last):
        self._record("mission_start", first, last)
        if len(self.mission_items) <= 1:
            return mav.MAV_RESULT_FAILED, "Mission: no mission"
        self.mode = CopterMode.AUTO
        self.mission_seq = max(1, first)
        return mav.MAV_RESULT_ACCEPTED, None

    def reposition(self, lat_e7, lon_e7, alt_m, frame, speed_m_s, yaw_deg, change_mode=True):
        self._record("reposition", lat_e7, lon_e7, alt_m, frame, speed_m_s, yaw_deg)
        if self.landed:
            return mav.MAV_RESULT_DENIED, "Reposition: take off first"
        return mav.MAV_RESULT_ACCEPTED, None

    def change_speed(self, speed_m_s, speed_type):
        self._record("change_speed", speed_m_s, speed_type)
        return mav.MAV_RESULT_ACCEPTED, None

    def condition_yaw(self, angle_deg, rate_deg_s, direction, relative):
        self._record("condition_yaw", angle_deg, rate_deg_s, direction, relative)
        return mav.MAV_RESULT_ACCEPTED, None

    def set_home(self, lat_e7, lon_e7, alt_m, relative):
        self._record("set_home", lat_e7, lon_e7, alt_m, relative)
        return mav.MAV_RESULT_ACCEPTED, None

    def mission_set_current(self, seq):
        self._record("mission_set_current", seq)
        self.mission_seq = seq
        return mav.MAV_RESULT_ACCEPTED, None

    def inject_failure(self, failure_unit, failure_type, instance):
        # The kinematic stand-in has no sensors to fail: answered as PX4 with SYS_FAILURE_EN 0.
        self._record("inject_failure", failure_unit, failure_type, instance)
        return mav.MAV_RESULT_DENIED, "Failure injection disabled (set SYS_FAILURE_EN 1)"

    def mission_updated(self, items):
        self._record("mission_updated", items)
        self.mission_items = items

    def geo_updated(self, mission_type, items):
        self._record("geo_updated", mission_type, items)

    def set_position_target(self, target):
        self._record("set_position_target", target)

    def set_attitude_target(self, target):
        self._record("set_attitude_target", target)

    def manual_control(self, x, y, z, r, buttons):
        self._record("manual_control", x, y, z, r, buttons)

    def rc_override(self, channels_us):
        self._record("rc_override", channels_us)

    # -- the outer loop ---------------------------------------------------------------------------
    def snapshot(self) -> VehicleSnapshot:
        present = (SensorBit.GYRO | SensorBit.ACCEL | SensorBit.MAG | SensorBit.ABS_PRESSURE
                   | SensorBit.GPS | SensorBit.ANGULAR_RATE_CONTROL | SensorBit.AHRS
                   | SensorBit.MOTOR_OUTPUTS | SensorBit.BATTERY | SensorBit.PREARM_CHECK)
        health = present if (self.prearm_ok or self.armed) else present & ~SensorBit.PREARM_CHECK
        t_ms = int((time.monotonic() - self._t0) * 1000)
        landed_state = (mav.MAV_LANDED_STATE_ON_GROUND if self.landed
                        else mav.MAV_LANDED_STATE_IN_AIR)
        axis_rows = tuple(PidTuningRow(axis, 1.0 * axis, 0.9 * axis, 0.0, 0.1, 0.01, 0.001)
                          for axis in (1, 2, 3, 4))
        return VehicleSnapshot(
            time_boot_ms=t_ms, armed=self.armed, custom_mode=self.mode,
            guided_enabled=self.mode in (CopterMode.GUIDED, CopterMode.AUTO, CopterMode.RTL),
            system_status=mav.MAV_STATE_ACTIVE if self.armed else mav.MAV_STATE_STANDBY,
            landed_state=landed_state, sensors_present=present, sensors_enabled=present,
            sensors_health=health, roll_rad=0.01, pitch_rad=-0.02, yaw_rad=math.radians(90.0),
            lat_e7=HOME[0], lon_e7=HOME[1], alt_msl_mm=HOME[2] + int(self.alt_m * 1000),
            alt_rel_mm=int(self.alt_m * 1000), home_set=True, home_lat_e7=HOME[0],
            home_lon_e7=HOME[1], home_alt_msl_mm=HOME[2], gps_fix_type=mav.GPS_FIX_TYPE_3D_FIX,
            gps_sats=12, gps_lat_e7=HOME[0], gps_lon_e7=HOME[1], gps_alt_msl_mm=HOME[2],
            battery_voltage_v=16.2, battery_current_a=12.5, battery_remaining_pct=87,
            servo_us=(1500, 1500, 1500, 1500), rc_channels_us=(1500,) * 8,
            accel_frd_m_s2=(0.0, 0.0, -9.80665), pid_rows=axis_rows,
            mission_seq=self.mission_seq,
            mission_state=(mav.MISSION_STATE_ACTIVE if self.mode == CopterMode.AUTO
                           else mav.MISSION_STATE_NOT_STARTED),
            mission_mode=1 if self.mode == CopterMode.AUTO else 0,
            flight_custom_version="deadbeef")

    def step(self, dt_s: float) -> None:
        if not self.landed:
            err = self.target_alt_m - self.alt_m
            self.alt_m += max(-self.CLIMB_M_S * dt_s, min(self.CLIMB_M_S * dt_s, err))
            if self.target_alt_m == 0.0 and self.alt_m <= 0.0:
                self.alt_m = 0.0
                self.landed = True

    def run_loop(self, server, rate_hz: float = 100.0) -> None:
        def loop():
            dt = 1.0 / rate_hz
            while not self._stop.is_set():
                if self.service_enabled:
                    server.service()
                self.step(dt)
                server.publish(self.snapshot())
                self._stop.wait(dt)
        server.publish(self.snapshot())
        self._thread = threading.Thread(target=loop, name="test-vehicle", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
