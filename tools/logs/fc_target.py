"""The command and the FC's own attitude target in a run log, the same for every FC.

Table 1 scores the true attitude twice (tools/benchmark/att_scoring.py): against the
scenario's command (the paper's definition, the headline) and against the
FC's own shaped target (what its attitude controller actually tracks). Both
references live in FC-agnostic channels, so an external autopilot's bridge
(ArduCopter here, PX4 likewise) logs them the way our FC's log has them:

- the command: `/setpoint`, SETPOINT records (shm/records.py: roll_rad,
  pitch_rad, yaw_rad, altitude_m, mask). Our FC's log holds the records the
  Simulator published; an external FC's bridge writes the command it
  forwarded, on the log's clock, with `CommandLog`.
- the FC's target: `/fc/target` (FC_TARGET_DTYPE), one row per report the FC
  sent (MAVLink ATTITUDE_TARGET: its attitude controller's shaped target),
  written with `TargetFeed`. A log without `/fc/target` is scored against
  /fc/status att_target_rad (our FC: its shaped target, exact per PWM tick).

/fc/target rows:
  sim_ns          the physics time the report was read (log clock, monotonic)
  fc_time_ns      the FC's own stamp of it (ATTITUDE_TARGET time_boot_ms x 1e6)
  att_target_rad  roll, pitch, yaw [rad] (ZYX Euler of the reported quaternion)
  source          1 = MAVLink ATTITUDE_TARGET
The stamp, not the arrival, places a report on the physics clock: a lockstep
SITL's clock is the physics clock plus a constant (it advances by the
timestamps we send), and a report is read some wall time after it was sent
while the physics runs on. The reader takes the constant as the smallest
(sim_ns - fc_time_ns) of the run, the report read soonest, and interpolates
between reports (att_scoring.target_at).
"""

from __future__ import annotations

import math
import threading

import numpy as np

from silbridge.shm.records import SETPOINT_DTYPE, Kind

TARGET_CHANNEL = "/fc/target"
COMMAND_CHANNEL = "/setpoint"
FC_TARGET_DTYPE = np.dtype([
    ("sim_ns", "<i8"),
    ("fc_time_ns", "<i8"),
    ("att_target_rad", "<f4", (3,)),
    ("source", "u1"),
])
SOURCE_ATTITUDE_TARGET = 1
MASK_ATTITUDE = 1            # bridge/setpoints.py: roll and pitch valid


class TargetFeed:
    """Reports from a MAVLink thread, written by the physics thread (the writer's owner).

    put() from any thread; drain(writer, t0_ns, end_ns) from the thread that
    owns the LogWriter, once per step once the log's clock has started (rows
    read before t0_ns are dropped); trim() while it has not.
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._rows: list = []
        self.count = 0

    def put(self, rx_sim_ns: int, fc_time_ns: int, roll: float, pitch: float, yaw: float,
            source: int = SOURCE_ATTITUDE_TARGET) -> None:
        if not all(math.isfinite(v) for v in (roll, pitch, yaw)):
            return
        with self._lock:
            self._rows.append((int(rx_sim_ns), int(fc_time_ns), roll, pitch, yaw, source))

    def drain(self, writer, t0_ns: int, end_ns: int | None = None) -> None:
        """Write the reports read in [t0_ns, end_ns) on the log clock (time 0 = t0_ns)."""
        if not self._rows:
            return
        with self._lock:
            rows, self._rows = self._rows, []
        for rx, fc_ns, r, p, y, src in rows:
            if rx >= t0_ns and (end_ns is None or rx < end_ns):
                writer.pack(TARGET_CHANNEL, rx - t0_ns, fc_ns, r, p, y, src)
                self.count += 1

    def trim(self, keep: int = 4096) -> None:
        """Before the log's clock starts: keep only the latest reports."""
        with self._lock:
            del self._rows[:-keep]


class CommandLog:
    """The command forwarded to an external FC, as SETPOINT records on `/setpoint`."""

    def __init__(self, writer):
        self.writer = writer
        self._rec = np.zeros(1, dtype=SETPOINT_DTYPE)
        self._rec["kind"] = Kind.SETPOINT
        self._last = None
        self._seq = 0

    def write(self, sim_ns: int, roll: float, pitch: float, yaw: float, alt_m: float) -> None:
        """Log the command in force from sim_ns (log clock) when it changed."""
        cmd = (roll, pitch, yaw, alt_m)
        if cmd == self._last:
            return
        self._last = cmd
        r = self._rec
        r["seq"] = self._seq
        self._seq += 1
        r["sim_ns"] = sim_ns
        r["roll_rad"], r["pitch_rad"], r["yaw_rad"], r["altitude_m"] = cmd
        r["mask"] = 7
        self.writer.write_records(r)
