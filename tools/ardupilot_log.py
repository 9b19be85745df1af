"""The run log of an ArduCopter flight, written from the bridge side.

ArduCopter's internals are out of reach, so the log holds what the physics
sees: every record of every step (sensor-model IMU, baro, mag, GNSS, ground
truth), the motor PWM of each servo packet on /pwm, and on /fc/status the
commanded attitude ArduCopter reported over MAVLink (ATTITUDE_TARGET, else
NAV_CONTROLLER_OUTPUT's nav_roll/nav_pitch), held and written once per
servo packet so tools/metrics.py reads it like our FC's status. Until the
first report the target is level (ArduCopter's target on the ground).

The log's clock starts at the take-off command (`start_at`): SITL's boot,
EKF alignment and arming happen before it on the physics clock, and a flight
log that starts at take-off puts ArduCopter's warm-up, transient and analysis
windows at the same place as our FC's (whose AutoFlight takes off at 0).
Scenario setpoint records are left out: they are not sent to ArduCopter.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from silbridge.shm.records import Kind

from .mcap_log import LogWriter

STATUS_CHANNEL = "/fc/status"
AP_STATUS_DTYPE = np.dtype([
    ("sim_ns", "<i8"),                 # physics time of the servo packet [ns]
    ("att_target_rad", "<f4", (3,)),   # commanded roll, pitch, yaw [rad]
    ("target_source", "u1"),           # 0 none yet (level), 1 ATTITUDE_TARGET,
                                       # 2 NAV_CONTROLLER_OUTPUT
])
SOURCE_NONE, SOURCE_ATTITUDE_TARGET, SOURCE_NAV_CONTROLLER = 0, 1, 2


class AttitudeTarget:
    """The latest commanded attitude, set by the MAVLink thread, read per physics step."""

    def __init__(self):
        self._lock = threading.Lock()
        self.value = (0.0, 0.0, 0.0)
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


class ArduPilotLogSink:
    """The `sink` of bridge.ardupilot_physics.ArduPilotPhysics: step() per servo packet."""

    def __init__(self, path, *, metadata: dict, target: AttitudeTarget, duration_s: float):
        self.writer = LogWriter(path, metadata=metadata)
        self.target = target
        self.duration_ns = int(round(duration_s * 1e9))
        self.t0_ns: int | None = None
        self.last_sim_ns = 0
        self._status = np.zeros(1, dtype=AP_STATUS_DTYPE)
        self._closed = False

    def start_at(self, sim_ns: int) -> None:
        """Start logging at this physics time (the take-off command); later calls are ignored."""
        if self.t0_ns is None:
            self.t0_ns = int(sim_ns)
            self.writer.event(0, "takeoff",
                              f"take-off command at physics time {sim_ns / 1e9:.3f} s",
                              physics_sim_ns=int(sim_ns))

    @property
    def done(self) -> bool:
        return self.t0_ns is not None and self.last_sim_ns - self.t0_ns >= self.duration_ns

    def step(self, recs, pwm, sim) -> None:
        self.last_sim_ns = sim.sim_ns
        t0 = self.t0_ns
        applied_ns = pwm["sim_ns"][0]    # when this packet's PWM took effect
        if t0 is None or applied_ns < t0 or applied_ns - t0 >= self.duration_ns:
            return
        keep = recs[recs["kind"] != Kind.SETPOINT].copy()
        keep["sim_ns"] -= t0
        self.writer.write_records(keep)
        p = pwm.copy()
        p["sim_ns"] -= t0
        p["imu_sim_ns"] -= t0
        self.writer.write_records(p)
        (roll, pitch, yaw), source = self.target.get()
        st = self._status
        st["sim_ns"] = p["sim_ns"][0]
        st["att_target_rad"][0] = (roll, pitch, yaw)
        st["target_source"] = source
        self.writer.write(STATUS_CHANNEL, st)

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        t = sim_ns - self.t0_ns if self.t0_ns is not None else 0
        self.writer.event(max(t, 0), kind, text, **fields)

    def close(self, **summary) -> None:
        if not self._closed:
            self._closed = True
            self.writer.close(**summary)
