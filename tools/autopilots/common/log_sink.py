"""The run log of a foreign autopilot's flight (ArduCopter or PX4), written from the bridge side.

The autopilot's internals are out of reach, so the log holds what the physics
sees: every record of every step (sensor-model IMU, baro, mag, GNSS, ground
truth), the motor PWM of each step on /pwm, one /fc/status row per step and one
/timing row per exchange on the link (ArduCopter: per servo packet; PX4: per PX4 step).
The words below are ArduCopter's; PX4's are its attitude target in OFFBOARD and its
HIL_ACTUATOR_CONTROLS (tools/autopilots/px4/flight.py, docs/logs.md).

/fc/status (AP_STATUS_DTYPE):
- att_target_rad: the commanded attitude tools/benchmark/metrics.py scores against the
  true attitude = the scenario's command as we sent it to ArduCopter
  (tools/autopilots/ardupilot/setpoints.py), exact in physics time. It is the raw
  command, before ArduCopter's input shaping (ATC_INPUT_TC, acceleration
  limits), like our FC's target with SB_SHAPE_EN = 0; so on steps and
  doublets ArduCopter's attitude error includes its shaping lag, which our
  FC's figure (scored against its shaped target) does not.
- ap_target_rad: ArduCopter's own attitude target (ATTITUDE_TARGET: its
  attitude controller's shaped target quaternion, ATT.DesRoll/DesPitch/DesYaw;
  NAV_CONTROLLER_OUTPUT's nav_roll/nav_pitch as a fallback), as last received
  over MAVLink: stamped at arrival, so it lags by the MAVLink stream period
  and the thread hand-over. NaN until the first report.
- target_source: where ap_target_rad came from (0 none yet, 1 ATTITUDE_TARGET,
  2 NAV_CONTROLLER_OUTPUT); forwarding: 1 once the scenario's commands are
  being sent to ArduCopter (before that it climbs in GUIDED take-off);
  thrust_cmd: the SET_ATTITUDE_TARGET thrust field last sent (0.5 = hold
  altitude).

/timing (tools/logs/log_format.py TIMING_DTYPE), the bridge side of the JSON link,
one row per stepped servo packet: sim_ns = when its PWM took effect;
imu_wall_ns = the servo packet's arrival; consume_wall_ns = our physics step
done; pwm_wall_ns = our JSON reply sent; loop_period_ns = the interval since
the previous servo packet (SITL's frame period, 0 for the first). So
`silbridge analyze` reports as latency_ms the physics latency (arrival ->
reply), as sensor_latency_ms the step's share of it, and as jitter_ms and
loop_period_ms SITL's frame period and its spread. SITL's own turnaround
(reply -> next servo packet: its FC frame plus two UDP hops, plus any
--speedup pacing sleep) is loop_period_ns - latency of the previous row.

The log's clock starts at the take-off command: SITL's boot, EKF alignment
and arming happen before it on the physics clock, and a flight log that
starts at take-off puts ArduCopter's warm-up, transient and analysis windows
at the same place as our FC's (whose AutoFlight takes off at 0). Time 0 is
the physics step at which the accepted MAV_CMD_NAV_TAKEOFF was written
(`pending_from`), not the step at which its acknowledgement was read: the
MAVLink thread reads that some wall-clock time later, while the physics runs
on and the vehicle already climbs. So the steps after each take-off command
are held, and written once its acceptance is known (`start_at`).
All calls come from the physics thread (the LogWriter belongs to one thread).
The Simulator's own SETPOINT records are left out: its profile runs on the
physics clock from boot; the forwarded profile runs from take-off and is in
att_target_rad.
"""

from __future__ import annotations

import math
import struct
import threading

import numpy as np

from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE, RECORD_SIZE, Kind

from silbridge.tools.logs.fc_target import FC_TARGET_DTYPE, TARGET_CHANNEL, CommandLog, TargetFeed
from silbridge.tools.logs.mcap_log import TIMING_CHANNEL, TIMING_DTYPE, LogWriter
from silbridge.tools.logs.rotor_log import RotorLog
from silbridge.shm.records import NS_PER_S

STATUS_CHANNEL = "/fc/status"
AP_STATUS_DTYPE = np.dtype([
    ("sim_ns", "<i8"),                 # physics time of the servo packet [ns]
    ("att_target_rad", "<f4", (3,)),   # the scenario's roll, pitch, yaw command sent [rad]
    ("ap_target_rad", "<f4", (3,)),    # ArduCopter's reported attitude target [rad]
    ("target_source", "u1"),           # of ap_target_rad: 0 none yet, 1 ATTITUDE_TARGET,
                                       # 2 NAV_CONTROLLER_OUTPUT
    ("forwarding", "u1"),              # 1 once the scenario's commands are sent
    ("thrust_cmd", "<f4"),             # SET_ATTITUDE_TARGET thrust last sent (0.5 = hold)
])
SOURCE_NONE, SOURCE_ATTITUDE_TARGET, SOURCE_NAV_CONTROLLER = 0, 1, 2
_U16, _I64 = struct.Struct("<H"), struct.Struct("<q")
_SETPOINT_KIND = int(Kind.SETPOINT)
_PWM_IMU_SIM_NS = PWM_DTYPE.fields["imu_sim_ns"][1]
HOLD_MAX_S = 10.0   # steps held between a take-off command and its acceptance, at most
_NAN3 = (math.nan, math.nan, math.nan)


class AttitudeTarget:
    """ArduCopter's latest reported attitude target, set by the MAVLink thread, read per step."""

    def __init__(self):
        self._lock = threading.Lock()
        self.value = _NAN3
        self.source = SOURCE_NONE

    def set(self, roll_rad: float, pitch_rad: float, yaw_rad: float, source: int) -> None:
        # NAV_CONTROLLER_OUTPUT is a fallback: never let it overwrite ATTITUDE_TARGET.
        if source == SOURCE_NAV_CONTROLLER and self.source == SOURCE_ATTITUDE_TARGET:
            return
        if not all(math.isfinite(v) for v in (roll_rad, pitch_rad, yaw_rad)):
            return
        with self._lock:
            self.value = (roll_rad, pitch_rad, yaw_rad)
            self.source = source

    def get(self) -> tuple:
        with self._lock:
            return self.value, self.source


class AutopilotLogSink:
    """The `sink` of the physics ends (bridge/autopilots/*/physics.py): step() and timing().

    command: the SetpointForwarder (its `command`, `engaged`, `last_thrust` are
    logged); None logs a level command (roll = pitch = yaw = 0).
    """

    def __init__(self, path, *, metadata: dict, target: AttitudeTarget, duration_s: float,
                 command=None, target_feed: TargetFeed | None = None):
        # Campaign runs leave the viewable /viz channels off (docs/logs.md).
        self.writer = LogWriter(path, metadata=metadata, viz_hz=0)
        self.writer.declare(TIMING_CHANNEL, TIMING_DTYPE)
        self.writer.declare(TARGET_CHANNEL, FC_TARGET_DTYPE)
        self.target_feed = target_feed
        self.commands = CommandLog(self.writer)
        # One struct pack per row (LogWriter.pack): numpy field stores cost ~1 us each.
        self.writer.declare(STATUS_CHANNEL, AP_STATUS_DTYPE)
        # /rotor: the motor model's rotor speeds per step (the caller declares config.rotor_hz).
        self.rotor = RotorLog(self.writer, None)
        self.target = target
        self.command = command
        self.duration_ns = int(round(duration_s * 1e9))
        self.t0_ns: int | None = None
        self.last_sim_ns = 0
        self._pending_ns: int | None = None   # a take-off command sent, not yet accepted
        self._held_steps: list = []           # its steps until then (recs, pwm, status row)
        self._held_timing: list = []
        self._hold_max = int(HOLD_MAX_S * 1e9)
        self._closed = False

    def pending_from(self, sim_ns: int) -> None:
        """A take-off command went out at this physics time: hold the steps from it on, to be
        written if ArduCopter accepts it (start_at) and dropped if another one follows."""
        self._pending_ns = int(sim_ns)
        self._held_steps = []
        self._held_timing = []

    def start_at(self, sim_ns: int) -> None:
        """Start the log at this physics time (the accepted take-off command), writing the
        steps held since pending_from(sim_ns); later calls are ignored."""
        if self.t0_ns is not None:
            return
        self.t0_ns = int(sim_ns)
        self.writer.event(0, "takeoff", f"take-off command at physics time {sim_ns / 1e9:.3f} s",
                          physics_sim_ns=int(sim_ns))
        held, self._held_steps = self._held_steps, []
        held_timing, self._held_timing = self._held_timing, []
        if self._pending_ns == self.t0_ns:
            end_ns = self.t0_ns + self.duration_ns
            for recs, pwm, row, rotor in held:
                if row[0] < end_ns:
                    self._write(recs, pwm, row, rotor)
            for row in held_timing:
                self.timing(*row)

    @property
    def done(self) -> bool:
        return self.t0_ns is not None and self.last_sim_ns - self.t0_ns >= self.duration_ns

    def _in_window(self, applied_ns) -> bool:
        t0 = self.t0_ns
        return t0 is not None and t0 <= applied_ns < t0 + self.duration_ns

    def _holding(self, applied_ns) -> bool:
        pending = self._pending_ns
        return self.t0_ns is None and pending is not None and \
            pending <= applied_ns < pending + self._hold_max

    def step(self, recs, pwm, sim, rotor=None) -> None:
        """One physics step's records and PWM; `rotor` (sim_ns, four rad/s) when the caller
        logs a step after the simulator moved on (PX4 sends several steps per packet)."""
        self.last_sim_ns = sim.sim_ns
        feed = self.target_feed
        if feed is not None:
            if self.t0_ns is not None:
                feed.drain(self.writer, self.t0_ns, self.t0_ns + self.duration_ns)
            elif sim.sim_ns % NS_PER_S == 0:
                feed.trim()
        applied_ns = int(pwm["sim_ns"][0])    # when this packet's PWM took effect
        in_window = self._in_window(applied_ns)
        if not in_window and not self._holding(applied_ns):
            return
        cmd = self.command
        (ar, ap, ay), source = self.target.get()
        if cmd is not None:
            roll, pitch, yaw, _ = cmd.command
            row = (applied_ns, roll, pitch, yaw, ar, ap, ay, source, cmd.engaged_ns is not None,
                   cmd.last_thrust)
        else:
            row = (applied_ns, 0.0, 0.0, 0.0, ar, ap, ay, source, 0, 0.5)
        if rotor is None:
            rotor = (sim.sim_ns, sim.rotor_rad_s())
        if in_window:
            self._write(recs, pwm, row, rotor)
        else:   # the Simulator reuses its record buffers: hold copies
            self._held_steps.append((recs.copy(), pwm.copy(), row, rotor))

    def _write(self, recs, pwm, row, rotor) -> None:
        t0 = self.t0_ns
        # The step's records and its PWM record, moved onto the log clock in their bytes:
        # a few struct calls where numpy masks, copies and field updates cost ~50 us.
        raw = bytearray(recs.tobytes())
        raw += pwm.tobytes()
        setpoints = False
        for off in range(0, len(raw), RECORD_SIZE):
            setpoints |= _U16.unpack_from(raw, off)[0] == _SETPOINT_KIND
            _I64.pack_into(raw, off + 8, _I64.unpack_from(raw, off + 8)[0] - t0)
        last = len(raw) - RECORD_SIZE + _PWM_IMU_SIM_NS
        _I64.pack_into(raw, last, _I64.unpack_from(raw, last)[0] - t0)
        out = np.frombuffer(raw, dtype=RECORD_DTYPE)
        if setpoints:   # the Simulator's profile (from boot): not this log's command
            out = out[out["kind"] != _SETPOINT_KIND]
        self.writer.write_records(out)
        self.rotor.write(rotor[0] - t0, rotor[1])
        self.writer.pack(STATUS_CHANNEL, row[0] - t0, *row[1:])
        alt = self.command.command[3] if self.command is not None else math.nan
        self.commands.write(row[0] - t0, row[1], row[2], row[3], alt)

    def timing(self, applied_ns: int, rx_wall_ns: int, done_wall_ns: int, tx_wall_ns: int,
               period_ns: int) -> None:
        """The JSON link's timing of one stepped packet (see the module text)."""
        if self._in_window(applied_ns):
            self.writer.pack(TIMING_CHANNEL, applied_ns - self.t0_ns, rx_wall_ns, done_wall_ns,
                             tx_wall_ns, period_ns)
        elif self._holding(applied_ns):
            self._held_timing.append((applied_ns, rx_wall_ns, done_wall_ns, tx_wall_ns,
                                      period_ns))

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        t = sim_ns - self.t0_ns if self.t0_ns is not None else 0
        self.writer.event(max(t, 0), kind, text, **fields)

    def close(self, **summary) -> None:
        if not self._closed:
            self._closed = True
            self.writer.close(**summary)
