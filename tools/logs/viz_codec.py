"""Fixed-size per-sample messages encoded a whole batch at a time, as MCAP Message records.

A viewable channel carries one small message per sample (Foxglove's Plot
panel plots one value per message), thousands per second; encoding each in
Python would cost microseconds per sample. Every message here has a fixed
size, so a batch of n messages is one numpy structured array of n rows, each
row a complete MCAP Message record (its head as tools/logs/mcap_layout.py declares it,
then the message bytes): constant bytes come from a
template row, variable ones are whole-column assignments, and the n records
go to the file as one buffer.

Two encodings, both fixed-size by construction:
- CDR (ros2msg schemas, our plot messages): a builtin_interfaces/Time stamp
  then float64 fields, all naturally aligned after the 4-byte header.
- protobuf (Foxglove's well-known schemas, foxglove.FrameTransform and
  foxglove.PoseInFrame, as the foxglove-sdk package defines them): every
  field is written, zeros included (proto3 parsers accept explicit
  defaults), doubles are fixed64, and the Timestamp's two varints are always
  5 bytes long (sim time up to 2**32 s) (a varint may carry redundant continuation bytes; protobuf
  parsers read up to 10), so nothing depends on the values' magnitudes.
"""

from __future__ import annotations

import numpy as np

from silbridge.tools.logs.log_schema import CDR_HEADER
from silbridge.tools.logs.mcap_layout import (MESSAGE_HEAD, MESSAGE_HEAD_FIELDS, OP_MESSAGE,
                                              RECORD_PREFIX)
from silbridge.shm.records import NS_PER_S

_TIME_DEF = "MSG: builtin_interfaces/msg/Time\nint32 sec\nuint32 nanosec\n"


def varint(v: int) -> bytes:
    out = bytearray()
    while True:
        b = v & 0x7F
        v >>= 7
        if v:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


_V5_SHIFT = np.array([0, 7, 14, 21, 28], dtype=np.uint32)
_V5_MORE = np.array([0x80, 0x80, 0x80, 0x80, 0], dtype=np.uint32)


def put_varint5(dest: np.ndarray, v: np.ndarray) -> None:
    """Write each value (< 2**32) as a 5-byte varint into dest, an (n, 5) uint8 column:
    continuation bits on the first 4 bytes whatever the value (fixed size). The five bytes
    of every value in one broadcast (the last one, v >> 28, is below 0x80 unmasked)."""
    v = np.asarray(v).astype(np.uint32)
    dest[...] = ((v[:, None] >> _V5_SHIFT) & 0x7F) | _V5_MORE


# -- message descriptions: lists of items ("const", bytes) | ("f8", name) | ("v5", name) --------

def pb_tag(field: int, wire: int) -> bytes:
    return varint(field << 3 | wire)


def _size(items: list) -> int:
    return sum(len(x) if k == "const" else (8 if k == "f8" else 5) for k, x in items)


def pb_message(field: int, items: list) -> list:
    """A nested message field (wire type 2) around fixed-size items."""
    return [("const", pb_tag(field, 2) + varint(_size(items)))] + items


def pb_string(field: int, text: str) -> list:
    data = text.encode()
    return [("const", pb_tag(field, 2) + varint(len(data)) + data)]


def pb_timestamp(field: int) -> list:
    """google.protobuf.Timestamp with variable columns 'sec' and 'nsec'."""
    return pb_message(field, [("const", pb_tag(1, 0)), ("v5", "sec"),
                              ("const", pb_tag(2, 0)), ("v5", "nsec")])


def pb_doubles(field: int, names: list[str]) -> list:
    """A message of double fields 1..n (foxglove.Vector3, foxglove.Quaternion)."""
    items = []
    for i, name in enumerate(names):
        items += [("const", pb_tag(i + 1, 1)), ("f8", name)]
    return pb_message(field, items)


def cdr_items(fields: list[str]) -> list:
    """CDR: header, Time stamp (columns 'sec', 'nsec'), float64 fields."""
    return [("const", CDR_HEADER), ("i4", "sec"), ("u4", "nsec")] + [("f8", f) for f in fields]


def ros2msg_text(title: str, fields: list[tuple[str, str]]) -> bytes:
    """The ros2msg schema of a cdr_items() message: fields = [(name, comment), ...]."""
    lines = [f"# {title}", "builtin_interfaces/Time stamp  # sim time of the sample"]
    lines += [f"float64 {name}  # {comment}" for name, comment in fields]
    return ("\n".join(lines) + "\n" + "=" * 80 + "\n" + _TIME_DEF).encode()


class FixedMessage:
    """A fixed-size message layout; encode() returns n MCAP Message records at once."""

    _CODES = {"f8": "<f8", "i4": "<i4", "u4": "<u4", "v5": ("u1", (5,))}

    def __init__(self, items: list):
        fields, template = list(MESSAGE_HEAD_FIELDS), {}
        for i, (kind, x) in enumerate(items):
            if kind == "const":
                name = f"_c{i}"
                fields.append((name, f"V{len(x)}"))
                template[name] = x
            else:
                fields.append((x, self._CODES[kind]))
        self.dtype = np.dtype(fields)                  # packed: a record is its bytes
        self.size = self.dtype.itemsize
        self.data_size = self.size - MESSAGE_HEAD.size
        self.v5 = {x for k, x in items if k == "v5"}
        row = np.zeros(1, dtype=self.dtype)
        for name, value in template.items():
            row[name] = np.frombuffer(value, dtype=f"V{len(value)}")[0]
        row["op"] = OP_MESSAGE
        row["length"] = self.size - RECORD_PREFIX.size   # after opcode and length
        self._template = row
        self._channel_rows = {}     # channel id -> the template's bytes with that id in

    def _template_bytes(self, channel_id: int) -> np.ndarray:
        row = self._channel_rows.get(channel_id)
        if row is None:
            row = self._template.copy()
            row["channel"] = channel_id
            row = self._channel_rows[channel_id] = row.view(np.uint8)
        return row

    def encode(self, channel_id: int, first_seq: int, sim_ns: np.ndarray, values: dict):
        """n records: log/publish time and the stamp from sim_ns, columns from values."""
        n = len(sim_ns)
        out = np.empty(n, self.dtype)
        # The constant bytes (channel id included) in one broadcast copy.
        out.view(np.uint8).reshape(n, self.size)[:] = self._template_bytes(channel_id)
        out["sequence"] = np.arange(first_seq, first_seq + n, dtype=np.uint64) & 0xFFFFFFFF
        t = np.maximum(np.asarray(sim_ns, dtype=np.int64), 0)
        out["log_time"] = t
        out["publish_time"] = t
        sec, nsec = np.divmod(t, NS_PER_S)
        for name, col in (("sec", sec), ("nsec", nsec)):
            if name in self.v5:
                put_varint5(out[name], col)
            else:
                out[name] = col
        for name, col in values.items():
            out[name] = col
        return out

    def data_of(self, records: np.ndarray) -> np.ndarray:
        """(n, data_size) uint8: the message bytes of each record (for the live view)."""
        return records.view(np.uint8).reshape(len(records), self.size)[:, MESSAGE_HEAD.size:]
