"""Which telemetry message goes out how often, per link.

ArduPilot keeps stream rates per channel, so do we: MAVSDK on 14540 asking for ATTITUDE at
50 Hz does not flood QGC on 14550. Two ways to set a rate, both as ArduCopter 4.5 treats them:
SET_MESSAGE_INTERVAL (per message; -1 off, 0 back to default) and the older
REQUEST_DATA_STREAM (per group of messages, rate in Hz, 0 or stop = off).

Messages nobody asked for stay off except the few a GCS needs before it asks anything:
HEARTBEAT (1 Hz, always sent unprompted), SYS_STATUS, EXTENDED_SYS_STATE, MISSION_CURRENT and
SYSTEM_TIME at 1 Hz.

Times are the microseconds of the server's StreamClock, the vehicle's simulated time
(stream_clock.py): rates are per simulated second, as ArduCopter SITL keeps them. Each send
carries a new vehicle snapshot, so a stream asked for faster than the vehicle publishes
(50 Hz) goes out once per snapshot. A link that fell behind (a stalled server thread) skips
missed sends rather than bursting them.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.stream_clock import StreamClock
from silbridge.mavlink.gcs.telemetry import ENCODERS

M = mav
DEFAULT_INTERVALS_US: dict[int, int] = {
    M.MAVLINK_MSG_ID_HEARTBEAT: 1_000_000,
    M.MAVLINK_MSG_ID_SYS_STATUS: 1_000_000,
    M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 1_000_000,
    M.MAVLINK_MSG_ID_MISSION_CURRENT: 1_000_000,
    M.MAVLINK_MSG_ID_SYSTEM_TIME: 1_000_000,
}

# REQUEST_DATA_STREAM groups (ArduCopter's GCS_MAVLINK_Copter stream lists, our subset).
STREAM_GROUPS: dict[int, tuple[int, ...]] = {
    M.MAV_DATA_STREAM_RAW_SENSORS: (M.MAVLINK_MSG_ID_RAW_IMU, M.MAVLINK_MSG_ID_SCALED_PRESSURE),
    M.MAV_DATA_STREAM_EXTENDED_STATUS: (M.MAVLINK_MSG_ID_SYS_STATUS,
                                        M.MAVLINK_MSG_ID_MISSION_CURRENT,
                                        M.MAVLINK_MSG_ID_GPS_RAW_INT,
                                        M.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT,
                                        M.MAVLINK_MSG_ID_FENCE_STATUS),
    M.MAV_DATA_STREAM_POSITION: (M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
                                 M.MAVLINK_MSG_ID_LOCAL_POSITION_NED),
    M.MAV_DATA_STREAM_RC_CHANNELS: (M.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW,
                                    M.MAVLINK_MSG_ID_RC_CHANNELS),
    M.MAV_DATA_STREAM_EXTRA1: (M.MAVLINK_MSG_ID_ATTITUDE, M.MAVLINK_MSG_ID_PID_TUNING),
    M.MAV_DATA_STREAM_EXTRA2: (M.MAVLINK_MSG_ID_VFR_HUD,),
    M.MAV_DATA_STREAM_EXTRA3: (M.MAVLINK_MSG_ID_SYSTEM_TIME, M.MAVLINK_MSG_ID_BATTERY_STATUS,
                               M.MAVLINK_MSG_ID_VIBRATION, M.MAVLINK_MSG_ID_EXTENDED_SYS_STATE,
                               M.MAVLINK_MSG_ID_EKF_STATUS_REPORT,
                               M.MAVLINK_MSG_ID_ESC_TELEMETRY_1_TO_4),
}

# Messages that may be streamed (everything with an encoder except the one-shot ones).
STREAMABLE = frozenset(set(ENCODERS) - {M.MAVLINK_MSG_ID_AUTOPILOT_VERSION})
# Messages ArduCopter accepts an interval for although this vehicle has nothing to put in them
# (no rangefinder): ACCEPTED and never sent, as ArduCopter without the sensor. Any other id is
# DENIED, as ArduCopter answers for messages it cannot send (MAVSDK asks for ALTITUDE,
# ODOMETRY, ACTUATOR_* and HIL_STATE_QUATERNION and gets COMMAND_DENIED from both).
NOTHING_TO_SEND = frozenset({M.MAVLINK_MSG_ID_DISTANCE_SENSOR})
MIN_INTERVAL_US = 4_000        # 250 Hz cap: the vehicle publishes snapshots at 50 Hz anyway
MAX_INTERVAL_US = 3_600_000_000


class StreamSchedule:
    """Per-link message intervals and next send times (microseconds of ``clock``)."""

    def __init__(self, clock: StreamClock):
        self.clock = clock
        self.intervals_us: dict[int, int] = dict(DEFAULT_INTERVALS_US)
        self._due_us: dict[int, int] = {mid: clock.now_us for mid in self.intervals_us}

    def set_interval(self, msg_id: int, interval_us: float | None) -> None:
        """interval_us None or <= 0: off. Clamped to [MIN_INTERVAL_US, MAX_INTERVAL_US]."""
        if interval_us is None or not interval_us > 0:
            self.intervals_us.pop(msg_id, None)
            self._due_us.pop(msg_id, None)
            return
        iv = round(min(max(interval_us, MIN_INTERVAL_US), MAX_INTERVAL_US))   # inf: the max
        now = self.clock.now_us
        self.intervals_us[msg_id] = iv
        # first send soon, then on the new period
        self._due_us[msg_id] = min(self._due_us.get(msg_id, now), now + iv)

    def set_default(self, msg_id: int) -> None:
        self.set_interval(msg_id, DEFAULT_INTERVALS_US.get(msg_id))

    def interval_us(self, msg_id: int) -> int:
        return self.intervals_us.get(msg_id, -1)

    def request_data_stream(self, stream_id: int, rate_hz: int, start: bool) -> None:
        groups = (list(STREAM_GROUPS) if stream_id == M.MAV_DATA_STREAM_ALL
                  else [stream_id] if stream_id in STREAM_GROUPS else [])
        interval = (1e6 / rate_hz) if (start and rate_hz > 0) else None
        for g in groups:
            for mid in STREAM_GROUPS[g]:
                self.set_interval(mid, interval)

    def due(self) -> list[int]:
        """The messages due at the clock's now; each one's next time moves on a period."""
        now = self.clock.now_us
        out = []
        for mid, t in self._due_us.items():
            if t <= now:
                out.append(mid)
                iv = self.intervals_us[mid]
                t += iv
                if t <= now:            # fell behind: skip, do not burst
                    t = now + iv
                self._due_us[mid] = t
        return out

    def next_due_us(self) -> int | None:
        return min(self._due_us.values()) if self._due_us else None
