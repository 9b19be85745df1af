"""Run logs as MCAP files: `LogWriter` during a run (here), `read_log` afterwards.

    from silbridge.tools.logs.mcap_log import LogWriter, read_log, RunLog, LogError

One MCAP channel per stream (/imu, /baro, /mag, /gnss, /gt_att, /gt_nav, /pwm,
/setpoint, /fc/status, /timing, ...). Rows of a channel are numpy structured
arrays; the writer copies their bytes into a per-channel queue
(tools/logs/log_stream.py) and, every `batch_rows` rows, turns a batch into
ONE ros2msg/CDR message whose rows are those bytes unchanged
(tools/logs/log_schema.py). So logging costs one small copy
per call, a few hundred ns, and a few microseconds per batch of 1024 rows;
`write_cycle` logs a whole loop cycle in one call. tools/logs/log_bench.py
measures the cost per physics step, on a replay and in the real loop.

Besides the streams a log holds:
- MCAP metadata "silbridge.run" (key "json"): the start metadata, written
  first and outside any chunk so even a log killed in its first second has
  it. Expected keys (tools/logs/integrity.py reads them, all optional):
  {"config": {"imu_hz", "pwm_hz", "baro_hz", "mag_hz", "gnss_hz",
  "physics_hz", "duration_s", "seed", "transport", "processes", "mode", ...},
  "scenario": {...}, "params": {name: value}, "software": {...}}.
  The same JSON is also the one message on "/run/metadata" so Foxglove shows it.
- "/events" (tools/logs/log_events.py): one JSON message per event, shaped as
  a foxglove.Log message (timestamp, level, name = kind, message = text) plus
  sim_ns and fields, so
  Foxglove's Log panel lists mode changes, parameter changes, disturbances
  and check results.
- MCAP metadata "silbridge.end", written by `close()`: rows per channel, last
  sim time and whatever the caller passed to close(). Its absence, like a
  missing MCAP footer, marks a log whose writer never finished.

Opening in Foxglove: open the .mcap file; in a Plot panel use a message path
such as `/imu.rows[:].gyro_frd_rad_s[2]` for Y and `/imu.t_s[:]` for X
("path (accumulated)" x-axis): every message carries up to `batch_rows`
rows, `t_s[i]` being the sim time of `rows[i]`. See docs/logs.md.

Lifetime and threading: `write`, `write_records` and `pack` copy the rows
before they return, so the caller may reuse or overwrite its arrays (ring
views included). A writer is not thread-safe: create, write and close it
from one thread. Every finished batch message goes to the file at once, and
every `flush_s` (0.5 s) of wall time or of sim time, whichever comes first,
the partial batches of every channel go too (`flush()`; checked every few
dozen calls, a clock read): so a process killed mid-run (SIGKILL, power cut)
leaves a file readable up to its last flush and loses at most ~0.5 s of any
stream, the 10 Hz GNSS as much as the 1 kHz IMU. With compression, the open
MCAP chunk is lost too.
"""

from __future__ import annotations

import json
from pathlib import Path
from time import monotonic_ns

import numpy as np

from silbridge.shm.records import DTYPES, RECORD_DTYPE, RECORD_SIZE, Kind
from silbridge.tools.logs.log_events import EventChannel
from silbridge.tools.logs.log_format import (EVENTS_CHANNEL, KIND_CHANNELS, LOG_FORMAT_VERSION,
                                        META_END, META_RUN, RUN_CHANNEL, STATUS_CHANNEL,
                                        TIMING_CHANNEL, TIMING_DTYPE, LogError, to_json)
from silbridge.tools.logs.log_reader import RunLog, read_log
from silbridge.tools.logs.log_stream import ChannelStream
from silbridge.tools.logs.mcap_writer import LibraryMcap, McapFile, McapSink, NullMcap
from silbridge.tools.logs.viz_log import VIZ_HZ_DEFAULT

# The public face of the log package: one import for writers and readers.
__all__ = ["LogWriter", "LogError", "RunLog", "read_log", "TIMING_DTYPE", "KIND_CHANNELS",
           "STATUS_CHANNEL", "TIMING_CHANNEL", "to_json"]


class LogWriter:
    """Writes one run's MCAP log.

    LogWriter(path, metadata=..., batch_rows=1024, compression="none")
      batch_rows   rows per MCAP message of every channel (memory: batch_rows
                   rows per channel); partial batches are written every FLUSH_NS
                   too, so a killed run loses at most ~0.5 s of any channel.
      compression  "none" (default): each message is written to the file as
                   it is made (tools/logs/mcap_writer.py, no MCAP chunks), so a
                   killed run keeps every finished batch; compressing costs
                   CPU in the loop. Every batch message carries its own
                   CRC-32, so corruption is detected either way.
                   "lz4" or "zstd": compressed MCAP chunks through the mcap
                   package (files 2-5x smaller, for archiving; slower; a
                   killed run loses the open chunk).
      chunk_bytes  MCAP chunk size when compressing.
      viz_hz       the viewable per-sample channels (/viz/..., tools/logs/viz_log.py) at
                   most this many messages per second each; 0: none.
      live         a tools.live_view.LiveView: the same viewable channels served
                   over Foxglove's WebSocket protocol while the run goes on; the
                   batches are then also cut at every capture flush. path None
                   with a live view: no file.
    Use as a context manager or call close(); both flush partial batches.
    """

    # Partial batches reach the file at least this often, in wall or sim time [ns].
    FLUSH_NS = 500_000_000
    # write_cycle / write_records read the clock every this many calls (a power of two).
    FLUSH_CHECK_CALLS = 64

    def __init__(self, path: str | Path | None, *, metadata: dict, batch_rows: int = 1024,
                 compression: str = "none", chunk_bytes: int = 1 << 20,
                 viz_hz: float = VIZ_HZ_DEFAULT, live=None):
        if batch_rows < 1:
            raise ValueError("batch_rows must be >= 1")
        if compression not in ("none", "lz4", "zstd"):
            raise ValueError("compression must be one of none, lz4, zstd")
        if viz_hz < 0:
            raise ValueError("viz_hz must be >= 0 (0: no viewable channels)")
        self.path = None if path is None else Path(path)
        library = f"silbridge-log/{LOG_FORMAT_VERSION}"
        self._mcap: McapSink
        try:
            if path is None:       # a live view without a file
                self._mcap = NullMcap()
            elif compression == "none":
                self._mcap = McapFile(self.path, library=library)
            else:
                self._mcap = LibraryMcap(self.path, compression, chunk_bytes, library=library)
        except OSError as exc:
            raise LogError(f"cannot create log {self.path}: {exc.strerror}; "
                           "choose a writable path") from exc
        self.batch_rows = batch_rows
        self._streams: dict[str, ChannelStream] = {}
        self._stage = bytearray()
        # Staged records are split by kind every 4 batches' worth: the split costs a
        # few numpy calls per kind, and a killed run loses at most this much.
        self._stage_bytes = 4 * batch_rows * RECORD_SIZE
        self._unknown: dict[int, int] = {}
        # write_cycle's cached views of the /fc/status and /timing queues.
        self._st_dtype = self._st_pending = self._st_limit = None
        self._capture_rebind = None  # capture by a C producer (capture_targets)
        self._capture_ticks = 0
        self._tm_pack = self._tm_pending = self._tm_limit = None
        self._events = EventChannel(self._mcap)
        self._closed = False
        self._calls = 0
        self._flush_wall_ns = monotonic_ns() + self.FLUSH_NS
        self._flush_sim_ns = self.FLUSH_NS
        run_json = to_json({"log_format": LOG_FORMAT_VERSION, **metadata})
        self._mcap.add_metadata(META_RUN, {"json": run_json})
        run_schema = self._mcap.register_schema(
            "silbridge.RunMetadata", "jsonschema",
            json.dumps({"title": "silbridge.RunMetadata", "type": "object"}).encode())
        run_channel = self._mcap.register_channel(RUN_CHANNEL, "json", run_schema)
        self._mcap.add_message(run_channel, 0, 0, 0, [run_json.encode()])
        # The viewable per-sample channels (tools/logs/viz_log.py), fed by each emitted batch;
        # with a live view, every capture flush also emits the partial batches.
        self._viz = None
        if viz_hz > 0 or live is not None:
            from silbridge.tools.logs.viz_log import VizChannels
            self._viz = VizChannels(None if path is None else self._mcap, metadata,
                                    viz_hz or VIZ_HZ_DEFAULT, live=live)
        self._flush_partial = live is not None

    # -- rows -------------------------------------------------------------
    def _open(self, channel: str, dtype: np.dtype) -> ChannelStream:
        if self._closed:
            raise ValueError("write after close()")
        if channel in (EVENTS_CHANNEL, RUN_CHANNEL):
            raise ValueError(f"{channel} is reserved; use event()")
        stream = ChannelStream(self._mcap, channel, dtype, self.batch_rows)
        self._streams[channel] = stream
        if self._viz is not None:
            stream.tap = self._viz.tap(channel, dtype)
        return stream

    def declare(self, channel: str, dtype: np.dtype) -> None:
        """Create a channel before its first rows (needed by pack())."""
        if channel not in self._streams:
            self._open(channel, np.dtype(dtype))

    def queue(self, channel: str) -> bytearray:
        """A declared channel's byte queue, for a C producer appending whole rows of its
        dtype (cut into batches like the captured channels)."""
        return self._streams[channel].pending

    def write(self, channel: str, arr: np.ndarray) -> None:
        """Append rows (a 1-D structured array) to a channel; the rows are copied.

        The first write fixes the channel's dtype. Cost: ~0.3 us per call plus
        tens of ns per row; an empty array returns at once.
        """
        stream = self._streams.get(channel)
        if stream is None:
            stream = self._open(channel, arr.dtype)
        if not len(arr):
            return
        if arr.dtype is not stream.in_dtype and arr.dtype != stream.in_dtype:
            raise ValueError(f"{channel}: rows of dtype {arr.dtype} after rows of "
                             f"{stream.in_dtype}; a channel keeps one dtype")
        pending = stream.pending
        pending += arr.tobytes()
        if len(pending) >= stream.batch_bytes:
            stream.drain()
        self._calls += 1
        if not self._calls & (self.FLUSH_CHECK_CALLS - 1):
            self._flush_if_due(int(arr["sim_ns"][-1]))

    def pack(self, channel: str, *values) -> None:
        """Append one row from its field values in dtype order, subarrays flattened.

        The cheapest path for rows the loop builds from Python numbers (the
        /timing row: no numpy array per step). The channel must exist
        (declare() or an earlier write()).
        """
        stream = self._streams[channel]
        if stream.packer is None:
            raise ValueError(f"{channel}: dtype {stream.in_dtype} cannot be packed; use write()")
        pending = stream.pending
        pending += stream.packer.pack(*values)
        if len(pending) >= stream.batch_bytes:
            stream.drain()

    def pack_rows(self, channel: str, arr: np.ndarray) -> None:
        """Append many rows (a structured array of the channel's dtype) as that many pack()
        calls would: the same bytes and batches, in one copy. Like pack() it leaves the
        flush clock alone, so a caller that switches from per-row pack() to this cuts its
        batches where it did before. The channel must exist (declare())."""
        stream = self._streams[channel]
        if arr.dtype != stream.in_dtype:
            raise ValueError(f"{channel}: rows of dtype {arr.dtype}, not {stream.in_dtype}")
        pending = stream.pending
        pending.extend(np.ascontiguousarray(arr))
        if len(pending) >= stream.batch_bytes:
            stream.drain()

    def write_records(self, records: np.ndarray) -> None:
        """Append 64-byte records of mixed kinds (RECORD_DTYPE or any kind's dtype).

        Records are staged as bytes and split by kind into their channels
        (KIND_CHANNELS) in bulk, so logging a physics step's records costs one
        copy. Do not also write() the same channels: the two paths would
        interleave out of order. Records of other kinds are not logged; the end
        summary counts them ("unknown_records").
        """
        if not len(records):
            return
        if records.itemsize != RECORD_SIZE:
            raise ValueError(f"records are {RECORD_SIZE} bytes, got {records.itemsize}")
        stage = self._stage
        stage.extend(records)
        if len(stage) >= self._stage_bytes:
            self._split_stage()
        self._calls += 1
        if not self._calls & (self.FLUSH_CHECK_CALLS - 1):
            self._flush_if_due(int(records[-1:].view(RECORD_DTYPE)["sim_ns"][0]))

    def write_cycle(self, records: np.ndarray, status: np.ndarray | None = None,
                    timing: tuple | None = None, pwm: np.ndarray | None = None) -> None:
        """One loop cycle in one call, the cheapest way to log a lockstep step.

        records  the sensor records the FC consumed (mixed kinds, as write_records)
        status   the FC status rows of the cycle, to /fc/status (may be empty)
        timing   the /timing row values (sim_ns, imu_wall_ns, consume_wall_ns,
                 pwm_wall_ns, loop_period_ns), as pack()
        pwm      PWM records (as write_records)
        Same result as the four separate calls, with about half their cost:
        the channels' queues are cached on the writer, so this is a handful of
        copies and comparisons.
        """
        if records.itemsize != RECORD_SIZE:
            raise ValueError(f"records are {RECORD_SIZE} bytes, got {records.itemsize}")
        stage = self._stage
        stage.extend(records)       # the buffer itself: no intermediate bytes object
        if status is not None and len(status):
            if status.dtype is self._st_dtype:
                pending = self._st_pending
                pending.extend(status)
                if len(pending) >= self._st_limit:
                    self._streams[STATUS_CHANNEL].drain()
            else:  # first status rows (opens and caches the channel), or a wrong dtype
                self.write(STATUS_CHANNEL, status)
                st = self._streams[STATUS_CHANNEL]
                self._st_dtype, self._st_pending, self._st_limit = \
                    st.in_dtype, st.pending, st.batch_bytes
        if timing is not None:
            if self._tm_pack is None:
                tm = self._streams.get(TIMING_CHANNEL) or self._open(TIMING_CHANNEL, TIMING_DTYPE)
                self._tm_pack, self._tm_pending, self._tm_limit = \
                    tm.packer.pack, tm.pending, tm.batch_bytes
            pending = self._tm_pending
            pending += self._tm_pack(*timing)
            if len(pending) >= self._tm_limit:
                self._streams[TIMING_CHANNEL].drain()
        if pwm is not None and len(pwm):
            if pwm.itemsize != RECORD_SIZE:
                raise ValueError(f"records are {RECORD_SIZE} bytes, got {pwm.itemsize}")
            stage.extend(pwm)
        if len(stage) >= self._stage_bytes:
            self._split_stage()
        self._calls += 1
        if not self._calls & (self.FLUSH_CHECK_CALLS - 1):
            self._flush_if_due(timing[0] if timing is not None else -1)

    # -- capture by a C producer (fc_sil's Core.bind_log) ---------------------
    # The producer appends raw 64-byte records straight to the queue of their kind's
    # channel (or, for a kind whose channel is not open yet, to the mixed stage) and
    # status rows to /fc/status; the loop calls cycle_tick() once per cycle with the
    # /timing row. Every CAPTURE_CHECK_TICKS ticks the writer cuts full batches and
    # splits the stage; when that opens channels it calls the rebind hook so the
    # producer writes the new kinds directly from then on.
    CAPTURE_CHECK_TICKS = 128

    def capture_targets(self, status_dtype: np.dtype) -> tuple:
        """(kind queues: tuple of 16 bytearray|None, stage, /fc/status queue, /timing
        queue) for a C producer. Opens /fc/status and /timing now; record channels open
        as their first records come through the stage."""
        st = self._streams.get(STATUS_CHANNEL) or self._open(STATUS_CHANNEL, status_dtype)
        if st.in_dtype != status_dtype:
            raise ValueError(f"{STATUS_CHANNEL} holds {st.in_dtype} rows, not {status_dtype}")
        tm = self._streams.get(TIMING_CHANNEL) or self._open(TIMING_CHANNEL, TIMING_DTYPE)
        self._tm_pack, self._tm_pending, self._tm_limit = tm.packer.pack, tm.pending, tm.batch_bytes
        queues = [None] * 16
        for kind, name in KIND_CHANNELS.items():
            stream = self._streams.get(name)
            if stream is not None and stream.in_dtype == DTYPES[Kind(kind)]:
                queues[kind] = stream.pending
        return tuple(queues), self._stage, st.pending, tm.pending

    def set_capture_rebind(self, rebind) -> None:
        """rebind(): called after the stage split opened channels (see capture_targets)."""
        self._capture_rebind = rebind
        self._capture_ticks = 0

    def cycle_tick(self, sim_ns: int, imu_wall_ns: int, consume_wall_ns: int,
                   pwm_wall_ns: int, loop_period_ns: int) -> None:
        """One cycle's /timing row; now and then, the batch boundaries of the queues."""
        self._tm_pending += self._tm_pack(sim_ns, imu_wall_ns, consume_wall_ns, pwm_wall_ns,
                                          loop_period_ns)
        self._capture_ticks += 1
        if self._capture_ticks >= self.CAPTURE_CHECK_TICKS:
            self._capture_ticks = 0
            self._capture_flush()

    def capture_flush(self) -> None:
        """Cut full batches and split the stage (a C producer that also writes the /timing
        rows calls this every CAPTURE_CHECK_TICKS cycles instead of cycle_tick)."""
        self._capture_flush()

    def _capture_flush(self) -> None:
        opened = len(self._streams)
        if len(self._stage) >= self._stage_bytes or \
                (self._stage and (self._flush_partial or self._rebind_pending())):
            self._split_stage()
        for stream in self._streams.values():
            if len(stream.pending) >= stream.batch_bytes or \
                    (self._flush_partial and stream.pending):
                stream.drain(final=self._flush_partial)
        tm = self._tm_pending
        # The C producer's cycles: their sim time is the newest /timing row's first field.
        sim_ns = int.from_bytes(tm[-TIMING_DTYPE.itemsize:][:8], "little", signed=True) \
            if tm else -1
        self._flush_if_due(sim_ns)
        if len(self._streams) != opened and self._capture_rebind is not None:
            self._capture_rebind()

    # -- crash safety: partial batches on a timer ------------------------------
    def _flush_if_due(self, sim_ns: int) -> None:
        """flush() when FLUSH_NS of wall time or of sim time passed since the last one."""
        now = monotonic_ns()
        if now >= self._flush_wall_ns or sim_ns >= self._flush_sim_ns:
            self.flush()
            self._flush_wall_ns = now + self.FLUSH_NS
            if sim_ns >= 0:
                self._flush_sim_ns = sim_ns + self.FLUSH_NS

    def flush(self) -> None:
        """Put every row written so far in the file: the staged records and each channel's
        partial batch become messages now (a SIGKILL then loses nothing before this)."""
        if self._closed:
            return
        opened = len(self._streams)
        if self._stage:
            self._split_stage()
        for stream in self._streams.values():
            if stream.pending:
                stream.drain(final=True)
        if len(self._streams) != opened and self._capture_rebind is not None:
            self._capture_rebind()

    def _rebind_pending(self) -> bool:
        """True while staged records are of a kind with no channel yet (split early, so the
        producer soon writes that kind directly)."""
        return any(KIND_CHANNELS.get(k) not in self._streams
                   for k in set(np.frombuffer(self._stage, RECORD_DTYPE)["kind"][-64:].tolist())
                   if k in KIND_CHANNELS)

    def _split_stage(self) -> None:
        staged = np.frombuffer(self._stage, dtype=RECORD_DTYPE)
        kinds = staged["kind"]
        # One stable sort groups the kinds into contiguous runs, in time order within each.
        grouped = staged[np.argsort(kinds, kind="stable")]
        counts = np.bincount(kinds)
        del staged, kinds  # release the view so the stage can be cleared
        self._stage.clear()
        raw = grouped.view(np.uint8)
        start = 0
        for kind, n in enumerate(counts.tolist()):
            if not n:
                continue
            if kind in KIND_CHANNELS:
                name, dtype = KIND_CHANNELS[kind], DTYPES[Kind(kind)]
                stream = self._streams.get(name) or self._open(name, dtype)
                if stream.in_dtype != dtype:
                    raise ValueError(f"{name} holds rows of {stream.in_dtype}, not records")
                # The kind's bytes go to its queue in one copy (no tobytes() first).
                stream.pending += memoryview(raw[start * RECORD_SIZE:(start + n) * RECORD_SIZE])
                if len(stream.pending) >= stream.batch_bytes:
                    stream.drain()
            else:
                # Not a record kind this log knows (a NONE slot, a newer kind):
                # counted in the end summary rather than failing a later call.
                self._unknown[kind] = self._unknown.get(kind, 0) + n
            start += n

    # -- events -----------------------------------------------------------
    def event(self, sim_ns: int, kind: str, text: str, **fields) -> None:
        """Log one event now (mode, param, disturbance, check, ...); fields: JSON values."""
        if self._closed:
            raise ValueError("event() after close()")
        self._events.write(sim_ns, kind, text, fields)

    # -- end --------------------------------------------------------------
    @property
    def rows_written(self) -> dict[str, int]:
        """Rows accepted per channel so far (including rows still buffered)."""
        out = {name: s.rows + s.buffered_rows() for name, s in self._streams.items()}
        if self._stage:
            kinds, counts = np.unique(np.frombuffer(bytes(self._stage), RECORD_DTYPE)["kind"],
                                      return_counts=True)
            for k, c in zip(kinds, counts):
                name = KIND_CHANNELS.get(int(k), str(int(k)))
                out[name] = out.get(name, 0) + int(c)
        return out

    def close(self, **summary) -> None:
        """Flush every partial batch, write the end summary and the MCAP index. Idempotent."""
        if self._closed:
            return
        try:
            if self._stage:
                self._split_stage()
            for stream in self._streams.values():
                stream.drain(final=True)
            if self._viz is not None:   # its CPU time goes in the end summary (log_bench)
                self._viz.close()
                summary = {"viz_cpu_s": self._viz.cpu_s, **summary}
            end = {"rows": {n: s.rows for n, s in self._streams.items()},
                   "events": self._events.count,
                   "unknown_records": {str(k): n for k, n in self._unknown.items()},
                   "end_sim_ns": max((s.last_sim_ns for s in self._streams.values()),
                                     default=0),
                   **summary}
            self._mcap.add_metadata(META_END, {"json": to_json(end)})
            self._mcap.finish()
        finally:
            self._closed = True
            self._mcap.close()  # after finish() a no-op; else the file reads as cut short

    def __enter__(self) -> "LogWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.close(error=f"{exc_type.__name__}: {exc}")
