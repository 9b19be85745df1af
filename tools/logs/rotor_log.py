"""The /rotor channel: each motor's rotor speed from the motor model, logged by the bridge.

The rotor speeds are JSBSim's `fcs/mN-omega-rad_s` (the motor lag's output, quadx
motors.xml), read after every physics step into the step kernel's state. They do not
travel through the ring (its records, and so the trace hashes, stay as they are): the
bridge side of the run writes them straight into the log, one row per physics step,
the ground-truth rate. The rate is declared in the start metadata as config.rotor_hz
(integrity.py checks the channel against it like /gt_att).

/rotor rows (ROTOR_DTYPE): sim_ns (end of the physics step), omega_rad_s[4] and
rpm[4], motors 1..4 in ArduCopter quad X order. /viz/rotor (tools/logs/viz_log.py)
shows them per sample for Foxglove's Plot panel.

Who writes them: in one process (`fly --processes 1`, the campaign) the log's own
sink, per step (RotorLog); an autopilot's bench log likewise. With the FC in its own
process the FC process writes the log and the rows cannot reach it without going
through the ring, so the bridge spools them to a file beside the log (RotorSpool)
and, once the FC process has finished the log, appends them as /rotor
(McapFile.reopen): the same rows, in the same file, without /viz/rotor.
"""

from __future__ import annotations

import math
import os
import struct

import numpy as np

ROTOR_CHANNEL = "/rotor"
ROTOR_DTYPE = np.dtype([
    ("sim_ns", "<i8"),                 # physics time at the end of the step [ns]
    ("omega_rad_s", "<f8", (4,)),      # rotor speed, motors 1..4 [rad/s]
    ("rpm", "<f8", (4,)),              # the same in revolutions per minute
])
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
RATE_KEY = "rotor_hz"                  # start metadata config key of the channel's rate


def declare_rate(metadata: dict, physics_hz: float) -> dict:
    """The start metadata with /rotor's rate (one row per physics step), for a log that
    carries the channel."""
    metadata.setdefault("config", {})[RATE_KEY] = physics_hz
    return metadata


class RotorLog:
    """Per physics step: rotor(sim_ns, omega) appends one /rotor row to a LogWriter.

    ``rotor_rad_s`` is a callable giving the four speeds now (Simulator.rotor_rad_s).
    A log whose clock starts elsewhere (an autopilot's take-off) calls write() itself."""

    def __init__(self, writer, rotor_rad_s):
        writer.declare(ROTOR_CHANNEL, ROTOR_DTYPE)
        self._pack = writer.pack
        self._pack_rows = writer.pack_rows
        self.rotor_rad_s = rotor_rad_s

    def __call__(self, sim_ns: int) -> None:
        self.write(sim_ns, self.rotor_rad_s())

    def write(self, sim_ns: int, omega) -> None:
        o1, o2, o3, o4 = omega
        k = RPM_PER_RAD_S
        self._pack(ROTOR_CHANNEL, sim_ns, o1, o2, o3, o4, o1 * k, o2 * k, o3 * k, o4 * k)

    def write_rows(self, sim_ns: np.ndarray, omega: np.ndarray) -> None:
        """A lockstep batch's rows at once (bridge/bridge_loop.py): the bytes write() would
        give row by row (a float64 product is the same in numpy as in Python), without a
        Python call per physics step."""
        self._pack_rows(ROTOR_CHANNEL, rotor_rows(sim_ns, omega))


def rotor_rows(sim_ns: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """ROTOR_DTYPE rows from step end times (n,) and rotor speeds (n, 4) [rad/s]."""
    rows = np.empty(len(sim_ns), ROTOR_DTYPE)
    rows["sim_ns"] = sim_ns
    rows["omega_rad_s"] = omega
    rows["rpm"] = omega * RPM_PER_RAD_S
    return rows


class RotorSpool:
    """The bridge's side of a two-process flight: rows to a spool file per physics step.

    It is the `sink` run_bridge gets there: `rotor(sim_ns)` after each step; `event`
    and `pwm_records` as a sink without a log has them (the FC process logs those).
    append_into(log_path) moves the rows into the FC's finished log."""

    FLUSH_ROWS = 1024
    pwm_records = None

    def __init__(self, spool_path, rotor_rad_s):
        self.path = str(spool_path)
        self._fh = open(self.path, "wb")
        self._row = struct.Struct("<q8d")
        assert self._row.size == ROTOR_DTYPE.itemsize
        self._buf = bytearray()
        self._rows = 0
        self.rotor_rad_s = rotor_rad_s
        # The bridge's hook: per step (a call) or per lockstep batch (write_rows), so a
        # logged two-process flight keeps the bridge's C batches (bridge_loop.bind_fc_process).
        self.rotor = self

    def __call__(self, sim_ns: int) -> None:
        o1, o2, o3, o4 = self.rotor_rad_s()
        k = RPM_PER_RAD_S
        self._buf += self._row.pack(sim_ns, o1, o2, o3, o4, o1 * k, o2 * k, o3 * k, o4 * k)
        self._rows += 1
        if self._rows % self.FLUSH_ROWS == 0:
            self._spill()

    def write_rows(self, sim_ns: np.ndarray, omega: np.ndarray) -> None:
        """A lockstep batch's rows, the bytes __call__ would spool step by step."""
        before = self._rows
        self._buf.extend(rotor_rows(sim_ns, omega))
        self._rows += len(sim_ns)
        if self._rows // self.FLUSH_ROWS != before // self.FLUSH_ROWS:
            self._spill()

    def _spill(self) -> None:
        self._fh.write(self._buf)
        self._buf.clear()

    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        """The bridge's events: the FC process logs the run's events, not this spool."""

    def close(self) -> None:
        if not self._fh.closed:
            self._fh.write(self._buf)
            self._buf.clear()
            self._fh.close()

    def discard(self) -> None:
        """Close and remove the spool (a run that ended without a finished log)."""
        self.close()
        if os.path.exists(self.path):
            os.unlink(self.path)

    def append_into(self, log_path, batch_rows: int = 1024) -> int:
        """Append the spooled rows to a finished log as /rotor; returns the rows appended.
        The spool file is removed. ValueError if the log is not a finished one of ours."""
        from silbridge.tools.logs.log_stream import ChannelStream
        from silbridge.tools.logs.mcap_writer import McapFile
        self.close()
        try:
            mcap = McapFile.reopen(log_path)
            try:
                stream = ChannelStream(mcap, ROTOR_CHANNEL, ROTOR_DTYPE, batch_rows)
                step = batch_rows * ROTOR_DTYPE.itemsize
                with open(self.path, "rb") as fh:
                    while chunk := fh.read(step):
                        stream.pending += chunk
                        stream.drain()
                stream.drain(final=True)
                mcap.finish()
            finally:
                mcap.close()
            return stream.rows
        finally:
            os.unlink(self.path)
