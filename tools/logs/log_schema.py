"""Batches of numpy rows as ROS 2 messages (ros2msg schema, CDR encoding).

A log channel carries rows of one numpy structured dtype (a sensor record, an
FC status row, a timing row). One MCAP message per row would cost microseconds
per row in Python, so rows are batched, and a batch is laid out so that its
rows need no encoding at all:

    builtin_interfaces/Time stamp   # sim time of the first row
    float64[] t_s                   # sim time of each row [s], for plotting
    uint32 row_size                 # bytes per row
    silbridge_msgs/ImuRow[] rows    # the rows, byte for byte as numpy holds them
    uint32 crc32                    # zlib CRC-32 of every byte before it

with `silbridge_msgs/ImuRow` listing the row's fields in memory order
(fixed-size arrays for subarray fields, uint8[n] for padding). CDR (XCDR1,
little endian, encapsulation 00 01 00 00) aligns every primitive to its size
counted from the end of the 4-byte header and adds nothing else; so when each
field of the row dtype sits at an offset that is a multiple of its element
size, the row size is a multiple of the largest alignment, and the rows start
8-aligned (the row_size word sees to that), the CDR bytes of `rows` ARE the
numpy bytes. The shm records (C structs with static_asserts) and the FC status
row qualify as they are; other dtypes are re-laid out once (`row_layout`).
Writing a batch is then one copy plus a CRC; reading it is np.frombuffer.

Foxglove decodes it as any ROS 2 message: plot `/imu.rows[:].gyro_frd_rad_s[2]`
against `/imu.t_s[:]`. The exact row dtype also travels in the channel
metadata as JSON (`dtype_to_json`), so the reader rebuilds arrays with their
field names, types, offsets and subarray shapes.
"""

from __future__ import annotations

import json
import re
import struct

import numpy as np
from silbridge.shm.records import NS_PER_S

try:
    # zlib's CRC-32 (ISO-HDLC: the same polynomial, bits and values), folded with carry-less
    # multiplies: ~28 GB/s against zlib 1.2.13's ~3.8 here. A 120 s bench log is ~50 MB of
    # batches, CRC'd once written and once read back: ~30 ms of zlib a run, ~4 ms of this.
    from fastcrc.crc32 import iso_hdlc as crc32
except ImportError:     # a process that hides fastcrc (`silbridge transport`'s -nofastcrc)
    from zlib import crc32

CDR_HEADER = b"\x00\x01\x00\x00"

# numpy kind+size -> ROS 2 primitive type name
_ROS_TYPES = {
    ("b", 1): "bool",
    ("i", 1): "int8", ("i", 2): "int16", ("i", 4): "int32", ("i", 8): "int64",
    ("u", 1): "uint8", ("u", 2): "uint16", ("u", 4): "uint32", ("u", 8): "uint64",
    ("f", 4): "float32", ("f", 8): "float64",
}

# ROS 2 field names: lower case, digits, single underscores, no trailing underscore.
_ROS_NAME = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")

# rosbag2's ros2msg convention: fields name a type as pkg/Type, the MSG lines
# of the appended dependencies as pkg/msg/Type.
_TIME_DEF = "MSG: builtin_interfaces/msg/Time\nint32 sec\nuint32 nanosec\n"
_SEPARATOR = "=" * 80


def is_dropped_field(name: str, base: np.dtype) -> bool:
    """Padding and reserved fields: logged as bytes, hidden when read back."""
    return base.kind == "V" or name.startswith("_") or name.startswith("reserved")


def _cdr_align(base: np.dtype) -> int:
    return 1 if base.kind == "V" else base.itemsize


def _is_cdr_layout(dtype: np.dtype) -> bool:
    align = 1
    for name in dtype.names:
        sub, offset = dtype.fields[name][:2]
        a = _cdr_align(sub.base)
        align = max(align, a)
        if offset % a:
            return False
    return dtype.itemsize % align == 0


def row_layout(dtype: np.dtype) -> np.dtype:
    """The dtype rows are logged in: `dtype` itself if CDR can lay it out byte for byte,
    else the same fields with C alignment (numpy align=True)."""
    if dtype.names is None:
        raise ValueError(f"log rows must have a structured dtype, got {dtype}")
    for name in dtype.names:
        base = dtype.fields[name][0].base
        if base.kind != "V" and (base.kind, base.itemsize) not in _ROS_TYPES:
            raise ValueError(f"field {name!r} has type {base} that the log cannot carry "
                             "(numbers, bools and padding only)")
        if base.itemsize > 1 and base.byteorder == ">":
            raise ValueError(f"field {name!r} is big-endian; log rows are little-endian")
    if _is_cdr_layout(dtype):
        return dtype
    fields = sorted(dtype.names, key=lambda n: dtype.fields[n][1])
    return np.dtype([(n, dtype.fields[n][0]) for n in fields], align=True)


def dtype_to_json(dtype: np.dtype) -> str:
    """The full layout (names, formats with shapes, offsets, itemsize) as JSON."""
    names = list(dtype.names)
    return json.dumps({
        "names": names,
        "formats": [[dtype.fields[n][0].base.str, list(dtype.fields[n][0].shape)] for n in names],
        "offsets": [dtype.fields[n][1] for n in names],
        "itemsize": dtype.itemsize})


def dtype_from_json(text: str) -> np.dtype:
    d = json.loads(text)
    return np.dtype({"names": d["names"],
                     "formats": [(t, tuple(s)) if s else t for t, s in d["formats"]],
                     "offsets": d["offsets"], "itemsize": d["itemsize"]})


def visible(rows: np.ndarray) -> np.ndarray:
    """A view of `rows` without its padding and reserved fields (no copy)."""
    keep = [n for n in rows.dtype.names if not is_dropped_field(n, rows.dtype.fields[n][0].base)]
    return rows if len(keep) == len(rows.dtype.names) else rows[keep]


def _row_msg(dtype: np.dtype) -> str:
    """ros2msg fields of one row, in memory order, gaps as uint8 padding."""
    lines, pos = [], 0
    for name in sorted(dtype.names, key=lambda n: dtype.fields[n][1]):
        sub, offset = dtype.fields[name][:2]
        if offset > pos:
            lines.append(f"uint8[{offset - pos}] pad_at_{pos}")
        if sub.base.kind == "V":
            lines.append(f"uint8[{sub.itemsize}] pad_at_{offset}")
        else:
            ros = _ROS_TYPES[(sub.base.kind, sub.base.itemsize)]
            count = int(np.prod(sub.shape)) if sub.shape else 0
            field = name if _ROS_NAME.match(name) else f"field_at_{offset}"
            lines.append(f"{ros}[{count}] {field}" if count else f"{ros} {field}")
        pos = offset + sub.itemsize
    if dtype.itemsize > pos:
        lines.append(f"uint8[{dtype.itemsize - pos}] pad_at_{pos}")
    return "\n".join(lines) + "\n"


def ros2msg_schema(row_dtype: np.dtype, type_stem: str, title: str) -> bytes:
    """The ros2msg text of a batch message of `row_dtype` rows (dependencies inlined)."""
    row_type = f"silbridge_msgs/{type_stem}Row"
    row_msg = f"silbridge_msgs/msg/{type_stem}Row"
    text = "\n".join([
        f"# {title}: t_s[i] is the sim time of rows[i]",
        "builtin_interfaces/Time stamp",
        "float64[] t_s",
        "uint32 row_size  # bytes per row",
        f"{row_type}[] rows",
        "uint32 crc32  # zlib CRC-32 of every message byte before this field",
        _SEPARATOR, f"MSG: {row_msg}", _row_msg(row_dtype).rstrip("\n"),
        _SEPARATOR, _TIME_DEF])
    return text.encode()


_STRUCT_CODES = {("b", 1): "?", ("i", 1): "b", ("u", 1): "B", ("i", 2): "h", ("u", 2): "H",
                 ("i", 4): "i", ("u", 4): "I", ("i", 8): "q", ("u", 8): "Q",
                 ("f", 4): "f", ("f", 8): "d"}


def row_struct(dtype: np.dtype) -> struct.Struct | None:
    """A struct packing one row of `dtype` from its flattened field values (None if it can't)."""
    fmt, pos = "<", 0
    for name, (sub, offset, *_) in sorted(dtype.fields.items(), key=lambda kv: kv[1][1]):
        code = _STRUCT_CODES.get((sub.base.kind, sub.base.itemsize))
        if code is None or offset < pos or sub.base.byteorder == ">":
            return None
        fmt += "x" * (offset - pos) + code * max(1, int(np.prod(sub.shape)))
        pos = offset + sub.itemsize
    fmt += "x" * (dtype.itemsize - pos)
    packer = struct.Struct(fmt)
    return packer if packer.size == dtype.itemsize else None


class BatchCodec:
    """Byte layout of batch messages of one row dtype (which must be a CDR layout).

    Offsets, from the start of the message (CDR header included), for n rows:
    stamp 4, t_s length 12, t_s 20, row_size 20+8n, rows length 24+8n,
    rows 28+8n, crc32 at the next multiple of 4 after the rows (+4 header).
    """

    def __init__(self, row_dtype: np.dtype):
        if not _is_cdr_layout(row_dtype):
            raise ValueError("row dtype is not a CDR layout; pass it through row_layout()")
        self.dtype = row_dtype
        self.itemsize = row_dtype.itemsize
        self._head = struct.Struct("<4siII4x")   # header, sec, nanosec, len(t_s), pad to 8
        self._mid = struct.Struct("<II")         # row_size, len(rows)

    def _crc_offset(self, n: int) -> int:
        body_end = 24 + 8 * n + n * self.itemsize
        return 4 + (body_end + 3) // 4 * 4

    def size(self, n: int) -> int:
        return self._crc_offset(n) + 4

    def encode(self, raw, sim_ns: np.ndarray) -> list:
        """One message, as a list of buffers to write in order, from the raw bytes of
        n rows (any bytes-like object, not copied) and their sim times [ns]."""
        n = len(sim_ns)
        first_ns = int(sim_ns[0])
        parts = [self._head.pack(CDR_HEADER, first_ns // NS_PER_S,
                                 first_ns % NS_PER_S, n),
                 (sim_ns * 1e-9).tobytes(), self._mid.pack(self.itemsize, n), raw]
        pad = self._crc_offset(n) - (28 + 8 * n + n * self.itemsize)
        if pad:
            parts.append(b"\x00" * pad)
        crc = 0
        for p in parts:
            crc = crc32(p, crc)
        parts.append(crc.to_bytes(4, "little"))
        return parts

    def check(self, data: bytes, index: int) -> tuple[int, str | None]:
        """(rows, why the message is damaged or None)."""
        if len(data) < 32:
            return 0, f"message {index} is {len(data)} bytes, too short for a batch"
        n = int.from_bytes(data[12:16], "little")
        if len(data) != self.size(n):
            return 0, f"message {index} of {n} rows has the wrong length {len(data)}"
        if crc32(memoryview(data)[:-4]) != int.from_bytes(data[-4:], "little"):
            return 0, f"message {index} fails its CRC-32 check"
        at = 20 + 8 * n
        row_size, rows = struct.unpack_from("<II", data, at)
        if row_size != self.itemsize or rows != n:
            return 0, f"message {index} holds rows of {row_size} bytes, not {self.itemsize}"
        return n, None

    def rows_bytes(self, data: bytes, n: int) -> memoryview:
        start = 28 + 8 * n
        return memoryview(data)[start:start + n * self.itemsize]


class CorruptChannel(ValueError):
    """A channel's messages are damaged; `rows` holds the rows of the messages before."""

    def __init__(self, reason: str, rows: np.ndarray):
        super().__init__(reason)
        self.rows = rows


def decode_messages(row_dtype: np.dtype, messages: list[bytes]) -> np.ndarray:
    """All rows of a channel's batch messages, in order (the full row dtype).

    Raises CorruptChannel, carrying the rows of the messages before the first
    damaged one, when a message fails its CRC or does not fit its layout.
    """
    codec = BatchCodec(row_dtype)
    chunks = []
    for i, m in enumerate(messages):
        n, reason = codec.check(m, i)
        if reason is not None:
            raise CorruptChannel(reason, _rows(row_dtype, chunks))
        chunks.append(codec.rows_bytes(m, n))
    return _rows(row_dtype, chunks)


def _rows(row_dtype: np.dtype, chunks: list) -> np.ndarray:
    """The chunks' bytes copied once into one writable array. Into numpy's own buffer, not
    a bytearray.join: numpy asks the kernel for huge pages on a large block, so copying a
    120 s log's ~50 MB of rows meets ~240 page faults instead of ~12,500 (19 ms against 28
    here)."""
    out = np.empty(sum(len(c) for c in chunks), dtype=np.uint8)
    dst, at = memoryview(out), 0
    for c in chunks:
        dst[at:at + len(c)] = c
        at += len(c)
    return out.view(row_dtype)
