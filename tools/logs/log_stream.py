"""One MCAP channel of a run log while it is written: the per-channel batch queue.

tools/logs/mcap_log.py's LogWriter keeps one ChannelStream per channel. The rows a
writer accepts (or a C producer appends) wait here as raw bytes; every `capacity`
rows they leave as one ros2msg/CDR batch message whose rows are those bytes
unchanged (tools/logs/log_schema.py), and each emitted batch may also feed a tap
(the viewable /viz channels, tools/logs/viz_log.py).
"""

from __future__ import annotations

import numpy as np

from silbridge.tools.logs.log_format import CHANNEL_DTYPE_KEY
from silbridge.tools.logs.log_schema import (BatchCodec, dtype_to_json, ros2msg_schema, row_layout,
                                        row_struct)


class ChannelStream:
    """One channel being written.

    Rows arrive as raw bytes appended to `pending` (arr.tobytes(): the cheapest
    safe copy of a small numpy array); every `capacity` rows, one batch of
    those bytes becomes one MCAP message with no per-row or per-field work
    (tools/logs/log_schema.py: the rows' bytes are their CDR encoding). A dtype
    that CDR cannot lay out byte for byte is re-laid out per batch.
    """

    __slots__ = ("name", "channel_id", "in_dtype", "row_dtype", "itemsize", "pending",
                 "batch_bytes", "capacity", "codec", "rows", "last_sim_ns", "packer", "_mcap",
                 "tap")

    def __init__(self, mcap, name: str, in_dtype: np.dtype, capacity: int):
        row_dtype = row_layout(in_dtype)
        if "sim_ns" not in row_dtype.names or row_dtype["sim_ns"] != np.dtype("<i8"):
            raise ValueError(f"rows of {name} need an int64 'sim_ns' field (message time)")
        self.codec = BatchCodec(row_dtype)
        stem = "".join(p.capitalize() for p in name.strip("/").replace("/", "_").split("_"))
        schema = ros2msg_schema(row_dtype, stem, f"silbridge batch of {name} rows")
        schema_id = mcap.register_schema(f"silbridge_msgs/msg/{stem}Batch", "ros2msg", schema)
        self.channel_id = mcap.register_channel(
            name, "cdr", schema_id, {CHANNEL_DTYPE_KEY: dtype_to_json(row_dtype)})
        self.name = name
        self.in_dtype = in_dtype
        self.row_dtype = row_dtype
        self.itemsize = in_dtype.itemsize
        self.pending = bytearray()
        self.capacity = capacity
        self.batch_bytes = capacity * in_dtype.itemsize
        self.rows = 0
        self.last_sim_ns = 0
        self.packer = row_struct(in_dtype)
        self._mcap = mcap
        self.tap = None     # tap(rows): each emitted batch, for the viewable channels

    def drain(self, final: bool = False) -> None:
        """Emit every full batch in `pending` (and, if final, the partial rest)."""
        pending, step = self.pending, self.batch_bytes
        while len(pending) >= step or (final and pending):
            take = min(step, len(pending))
            # One copy out; the temporary view is gone before `pending` shrinks.
            raw = bytes(memoryview(pending)[:take])
            del pending[:take]
            self._emit(raw)

    def _emit(self, raw: bytes) -> None:
        rows = np.frombuffer(raw, dtype=self.in_dtype)
        if self.row_dtype is not self.in_dtype:
            aligned = np.zeros(len(rows), dtype=self.row_dtype)
            for name in self.in_dtype.names:
                aligned[name] = rows[name]
            rows, raw = aligned, aligned.tobytes()
        sim_ns = rows["sim_ns"]
        first_ns = max(int(sim_ns[0]), 0)
        self.last_sim_ns = max(self.last_sim_ns, int(sim_ns[-1]))
        self._mcap.add_message(self.channel_id, first_ns, first_ns, self.rows & 0xFFFFFFFF,
                               self.codec.encode(raw, sim_ns))
        self.rows += len(rows)
        if self.tap is not None:
            self.tap(rows)

    def buffered_rows(self) -> int:
        return len(self.pending) // self.itemsize
