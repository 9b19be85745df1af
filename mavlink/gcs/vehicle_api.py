"""The contract between the GCS server (this package) and the vehicle (fc_sil).

The server runs on its own thread and must never block the control loop, so the two sides
meet in exactly three places, all defined here:

* ``VehicleSnapshot``: an immutable picture of everything telemetry needs. The vehicle builds
  a new one at its outer-loop rate (50 to 100 Hz) and publishes it with one reference swap;
  the server only ever reads whole snapshots, so it never sees a half-updated state.
* ``VehicleCommands``: what a GCS may ask of the vehicle. The server never calls these
  methods itself; it queues ``VehicleCall`` objects on a ``CommandChannel`` and the vehicle
  executes them on its own thread when it calls ``GcsServer.service()``. Replies travel back
  through the same channel and become COMMAND_ACKs.
* ``ParamStore``: the vehicle's parameter table. Unlike commands, ``set`` is called directly
  from the GCS thread (a PARAM_SET must take effect at once and be echoed with the stored
  value), so implementations apply it under their own lock or at the next step boundary.

Units and frames are in the field names: ``_e7`` degrees * 1e7, ``_mm`` millimetres,
``_ned``/``_frd`` world/body frames, ``_cdeg`` centidegrees.
"""

from __future__ import annotations

import collections
import dataclasses
import itertools
import logging
import math
import threading
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol, Sequence, runtime_checkable

from pymavlink.dialects.v20 import ardupilotmega as mav

log = logging.getLogger(__name__)

# ArduCopter release whose parameter names and MAVLink behaviour we follow.
COPTER_VERSION = (4, 5, 7)


def flight_sw_version(major: int, minor: int, patch: int,
                      fw_type: int = mav.FIRMWARE_VERSION_TYPE_OFFICIAL) -> int:
    """AUTOPILOT_VERSION.flight_sw_version packing used by ArduPilot."""
    return (major << 24) | (minor << 16) | (patch << 8) | fw_type


# ArduCopter flight mode numbers (custom_mode).
class CopterMode:
    STABILIZE = 0
    ACRO = 1
    ALT_HOLD = 2
    AUTO = 3
    GUIDED = 4
    LOITER = 5
    RTL = 6
    CIRCLE = 7
    LAND = 9
    POSHOLD = 16
    BRAKE = 17
    SMART_RTL = 21


# SYS_STATUS onboard_control_sensors bits the vehicle reports.
class SensorBit:
    GYRO = mav.MAV_SYS_STATUS_SENSOR_3D_GYRO
    ACCEL = mav.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    MAG = mav.MAV_SYS_STATUS_SENSOR_3D_MAG
    ABS_PRESSURE = mav.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    GPS = mav.MAV_SYS_STATUS_SENSOR_GPS
    ANGULAR_RATE_CONTROL = mav.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    ATTITUDE_STABILIZATION = mav.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    YAW_POSITION = mav.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    Z_ALTITUDE_CONTROL = mav.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    XY_POSITION_CONTROL = mav.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    MOTOR_OUTPUTS = mav.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    AHRS = mav.MAV_SYS_STATUS_AHRS
    BATTERY = mav.MAV_SYS_STATUS_SENSOR_BATTERY
    PREARM_CHECK = mav.MAV_SYS_STATUS_PREARM_CHECK
    GEOFENCE = mav.MAV_SYS_STATUS_GEOFENCE


@dataclass(frozen=True, slots=True)
class PidTuningRow:
    """One PID_TUNING row (ArduPilot AP_PIDInfo); rates in deg/s for attitude axes."""
    axis: int            # PID_TUNING_AXIS: 1 roll, 2 pitch, 3 yaw, 4 accel z
    desired: float
    achieved: float
    ff: float
    p: float
    i: float
    d: float
    srate: float = 0.0   # slew rate
    pdmod: float = 0.0   # P/D modifier from slew limiting


@dataclass(frozen=True, slots=True)
class NavControllerOutput:
    nav_roll_deg: float = 0.0
    nav_pitch_deg: float = 0.0
    nav_bearing_deg: int = 0
    target_bearing_deg: int = 0
    wp_dist_m: int = 0
    alt_error_m: float = 0.0
    aspd_error_m_s: float = 0.0
    xtrack_error_m: float = 0.0


@dataclass(frozen=True, slots=True)
class EscRow:
    """One ESC's latest telemetry, as ESC_TELEMETRY_1_TO_4 reports it (units in the names)."""
    motor: int                      # 0-based motor index
    temperature_c: float
    voltage_v: float
    current_a: float
    consumption_mah: float
    rpm: float
    count: int                      # telemetry reports received from this ESC


@dataclass(frozen=True, slots=True)
class VehicleSnapshot:
    """Everything the telemetry streams read, as of one instant of the vehicle loop."""
    time_boot_ms: int = 0
    # state
    armed: bool = False
    custom_mode: int = CopterMode.STABILIZE
    guided_enabled: bool = False          # horizontal position controller active
    system_status: int = mav.MAV_STATE_BOOT
    landed_state: int = mav.MAV_LANDED_STATE_ON_GROUND
    sensors_present: int = 0
    sensors_enabled: int = 0
    sensors_health: int = 0               # PREARM_CHECK healthy when armed or checks pass
    load_permille: int = 0                # main loop load
    # attitude (world NED, body FRD)
    roll_rad: float = 0.0
    pitch_rad: float = 0.0
    yaw_rad: float = 0.0
    rollspeed_rad_s: float = 0.0
    pitchspeed_rad_s: float = 0.0
    yawspeed_rad_s: float = 0.0
    q_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    # position estimate
    lat_e7: int = 0
    lon_e7: int = 0
    alt_msl_mm: int = 0
    alt_rel_mm: int = 0
    vel_ned_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    pos_ned_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    # home
    home_set: bool = False
    home_lat_e7: int = 0
    home_lon_e7: int = 0
    home_alt_msl_mm: int = 0
    home_epoch: int = 0                   # +1 whenever ArduCopter would announce a new home
    home_ned_m: tuple[float, float, float] = (0.0, 0.0, 0.0)   # about the estimator origin
    # estimator health (EKF_STATUS_REPORT: EKF_* flags and normalised test ratios)
    ekf_flags: int = 0
    ekf_vel_var: float = 0.0
    ekf_pos_h_var: float = 0.0
    ekf_pos_v_var: float = 0.0
    ekf_compass_var: float = 0.0
    # geofence (FENCE_STATUS is sent only while the fence is enabled, as ArduCopter does)
    fence_enabled: bool = False
    fence_breach_status: int = 0
    fence_breach_count: int = 0
    fence_breach_type: int = mav.FENCE_BREACH_NONE
    fence_breach_time_ms: int = 0
    fence_mitigation: int = mav.FENCE_MITIGATE_NONE
    # GNSS receiver (raw, not the estimate)
    gps_fix_type: int = mav.GPS_FIX_TYPE_NO_GPS
    gps_sats: int = 0
    gps_lat_e7: int = 0
    gps_lon_e7: int = 0
    gps_alt_msl_mm: int = 0
    gps_eph_cm: int = 65535
    gps_epv_cm: int = 65535
    gps_vel_cm_s: int = 0
    gps_cog_cdeg: int = 65535
    # battery
    battery_voltage_v: float = 0.0
    battery_current_a: float = -1.0       # -1: not measured
    battery_remaining_pct: int = -1       # -1: not estimated
    battery_consumed_mah: float = -1.0
    # actuators and pilot input
    servo_us: tuple[int, ...] = ()        # up to 16 outputs
    rc_channels_us: tuple[int, ...] = ()  # up to 18 inputs (incl. overrides)
    rc_rssi: int = 255                    # 255: unknown
    # raw sensors (body FRD)
    accel_frd_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gyro_frd_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mag_frd_gauss: tuple[float, float, float] = (0.0, 0.0, 0.0)
    imu_temperature_degc: float = 25.0
    baro_press_hpa: float = 1013.25
    baro_temp_degc: float = 25.0
    # VFR_HUD
    airspeed_m_s: float = 0.0
    groundspeed_m_s: float = 0.0
    throttle_pct: int = 0
    climb_m_s: float = 0.0
    nav: NavControllerOutput = field(default_factory=NavControllerOutput)
    pid_rows: tuple[PidTuningRow, ...] = ()
    # mission progress (total comes from the mission store)
    mission_seq: int = 0
    mission_state: int = mav.MISSION_STATE_NOT_STARTED
    mission_mode: int = 0                 # 1 when in AUTO
    # vibration
    vibration_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)
    clipping: tuple[int, int, int] = (0, 0, 0)
    # ESC telemetry (ESC_TELEMETRY_1_TO_4 / _5_TO_8): reporting ESCs only, motor order
    esc: tuple[EscRow, ...] = ()
    # identity
    flight_sw_version: int = flight_sw_version(*COPTER_VERSION)
    flight_custom_version: str = "00000000"   # 8 ASCII chars, e.g. the git hash
    board_version: int = 0
    uid: int = 0


class SnapshotBox:
    """Latest published snapshot; one reference swap, so readers never see a torn state."""

    def __init__(self, initial: VehicleSnapshot | None = None):
        self._snapshot = initial if initial is not None else VehicleSnapshot()

    def publish(self, snapshot: VehicleSnapshot) -> None:
        self._snapshot = snapshot

    @property
    def latest(self) -> VehicleSnapshot:
        return self._snapshot


# ---------------------------------------------------------------------------------------------
# Setpoints decoded from GUIDED/offboard messages (passed to the vehicle as they arrive).

@dataclass(frozen=True, slots=True)
class PositionTarget:
    """SET_POSITION_TARGET_LOCAL_NED or _GLOBAL_INT, type_mask as in the common dialect."""
    time_boot_ms: int
    frame: int
    type_mask: int
    is_global: bool
    # local: x, y, z in metres (NED); global: lat_e7, lon_e7 in x, y and altitude (m) in z
    x: float
    y: float
    z: float
    vel_ned_m_s: tuple[float, float, float]
    acc_ned_m_s2: tuple[float, float, float]
    yaw_rad: float
    yaw_rate_rad_s: float
    source_system: int


@dataclass(frozen=True, slots=True)
class AttitudeTarget:
    time_boot_ms: int
    type_mask: int
    q_wxyz: tuple[float, float, float, float]
    body_rates_rad_s: tuple[float, float, float]
    thrust: float                          # 0..1
    source_system: int


# MAV_RESULT plus an optional human-readable reason (sent as STATUSTEXT when present).
CommandReply = tuple[int, str | None]


@runtime_checkable
class VehicleCommands(Protocol):
    """Requests a GCS can make. Called only on the vehicle thread, from GcsServer.service().

    Methods that answer a COMMAND_LONG/INT return ``(MAV_RESULT, reason or None)``; when the
    result is not ACCEPTED the reason is sent as a STATUSTEXT (write it the way ArduPilot
    would, e.g. "PreArm: GPS not healthy"). Setpoint methods return nothing.
    """

    def arm(self, force: bool) -> CommandReply: ...
    def disarm(self, force: bool) -> CommandReply: ...
    def set_mode(self, custom_mode: int) -> CommandReply: ...
    def takeoff(self, alt_m: float) -> CommandReply: ...
    def land(self) -> CommandReply: ...
    def rtl(self) -> CommandReply: ...
    def mission_start(self, first: int, last: int) -> CommandReply: ...
    def reposition(self, lat_e7: int, lon_e7: int, alt_m: float, frame: int,
                   speed_m_s: float, yaw_deg: float, change_mode: bool) -> CommandReply: ...
    def change_speed(self, speed_m_s: float, speed_type: float) -> CommandReply: ...
    def condition_yaw(self, angle_deg: float, rate_deg_s: float, direction: int,
                      relative: bool) -> CommandReply: ...
    def set_home(self, lat_e7: int | None, lon_e7: int | None, alt_m: float,
                 relative: bool) -> CommandReply: ...
    def mission_set_current(self, seq: int) -> CommandReply: ...
    def inject_failure(self, failure_unit: int, failure_type: int,
                       instance: int) -> CommandReply: ...
    def mission_updated(self, items: tuple["MissionItem", ...]) -> None: ...
    def geo_updated(self, mission_type: int, items: tuple["MissionItem", ...]) -> None: ...
    def set_position_target(self, target: PositionTarget) -> None: ...
    def set_attitude_target(self, target: AttitudeTarget) -> None: ...
    def manual_control(self, x: int, y: int, z: int, r: int, buttons: int) -> None: ...
    def rc_override(self, channels_us: tuple[int, ...]) -> None: ...


@runtime_checkable
class ParamStore(Protocol):
    """The vehicle's parameter table. ``set`` runs on the GCS thread (see module text)."""

    def names(self) -> Sequence[str]:
        """All names in index order; the order never changes while the process runs."""
        ...

    def get(self, name: str) -> tuple[float, int]:
        """(value, MAV_PARAM_TYPE); KeyError for an unknown name."""
        ...

    def set(self, name: str, value: float) -> str | None:
        """Store value; return None, or the reason it was refused (value then unchanged).

        The server has already refused NaN/inf and, for integer types, rounded the value to
        an ``int`` that fits the type; the store checks its own min/max. A short reason
        ("0.9 out of range 0..0.5") reads best in the STATUSTEXT a GCS shows."""
        ...


# ---------------------------------------------------------------------------------------------
# Missions

@dataclass(frozen=True, slots=True)
class MissionItem:
    """One MISSION_ITEM_INT; x, y are degrees*1e7 in global frames (raw int otherwise)."""
    seq: int
    frame: int
    command: int
    current: int = 0
    autocontinue: int = 1
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0
    y: int = 0
    z: float = 0.0
    mission_type: int = mav.MAV_MISSION_TYPE_MISSION

    def same_content(self, other: "MissionItem") -> bool:
        """Equal, treating NaN params as equal to NaN (NaN means 'unchanged' in MAVLink)."""
        def eq(a, b):
            return a == b or (isinstance(a, float) and isinstance(b, float)
                              and math.isnan(a) and math.isnan(b))
        return all(eq(getattr(self, f.name), getattr(other, f.name))
                   for f in dataclasses.fields(self))


# ---------------------------------------------------------------------------------------------
# Command hand-off between the GCS thread and the vehicle thread

@dataclass(slots=True)
class VehicleCall:
    method: str                      # a VehicleCommands method name
    args: tuple[Any, ...]
    token: int | None = None         # None: fire and forget (setpoints, notifications)


class CommandChannel:
    """Thread-safe queue of VehicleCalls (GCS -> vehicle) and their replies (vehicle -> GCS).

    Bounded so a stalled vehicle cannot make the GCS thread grow without limit; a call that
    has not started yet can be cancelled (the server then answers TEMPORARILY_REJECTED), a
    call already running cannot (its reply will come).
    """

    def __init__(self, capacity: int = 256, wake: Callable[[], None] | None = None):
        self._lock = threading.Lock()
        self._calls: collections.deque[VehicleCall] = collections.deque()
        self._replies: collections.deque[tuple[int, CommandReply]] = collections.deque()
        self._capacity = capacity
        self._wake = wake
        self._tokens = itertools.count(1)

    def new_token(self) -> int:
        return next(self._tokens)

    def submit(self, call: VehicleCall) -> bool:
        with self._lock:
            if len(self._calls) >= self._capacity:
                return False
            self._calls.append(call)
            return True

    def cancel(self, token: int) -> bool:
        """Remove a call that has not started; False if it already ran or is running."""
        with self._lock:
            for call in self._calls:
                if call.token == token:
                    self._calls.remove(call)
                    return True
        return False

    def pending(self) -> int:
        with self._lock:
            return len(self._calls)

    def service(self, vehicle: VehicleCommands, max_calls: int = 64) -> int:
        """Run queued calls on the caller's (vehicle) thread; returns how many ran."""
        ran = 0
        while ran < max_calls:
            with self._lock:
                if not self._calls:
                    break
                call = self._calls.popleft()
            ran += 1
            try:
                result = getattr(vehicle, call.method)(*call.args)
            except Exception as exc:  # noqa: BLE001 - a vehicle bug must not kill its loop
                log.exception("vehicle call %s failed", call.method)
                result = (mav.MAV_RESULT_FAILED, f"{call.method} failed: {exc}")
            if call.token is not None:
                reply = _normalise_reply(result)
                with self._lock:
                    self._replies.append((call.token, reply))
        if ran and self._wake is not None:
            self._wake()
        return ran

    def take_replies(self) -> list[tuple[int, CommandReply]]:
        with self._lock:
            out = list(self._replies)
            self._replies.clear()
        return out


def _normalise_reply(result: Any) -> CommandReply:
    if isinstance(result, tuple) and len(result) == 2:
        return int(result[0]), (None if result[1] is None else str(result[1]))
    if isinstance(result, int):
        return result, None
    return mav.MAV_RESULT_FAILED, f"vehicle returned {result!r}"
