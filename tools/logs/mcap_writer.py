"""A minimal MCAP writer: unchunked records straight to the file, then the summary.

Why not the `mcap` package's Writer for the default, uncompressed logs: it
builds every record in a BytesIO, copies it out and then writes it: three
copies of each batch message, about half a microsecond per physics step of
a logged run (tools/logs/log_bench.py). Here a message record is one os.writev()
of its header and the caller's buffers, gathered by the kernel, and every
record is in the file when the call returns (a killed run keeps it).

What it writes (MCAP spec, mcap.dev/spec): magic, Header, then Schema,
Channel, Message and Metadata records in call order; on finish, DataEnd and
a summary section (schemas, channels, Statistics, MetadataIndex records and
their SummaryOffsets), the Footer (summary CRC included) and the magic. No
chunk or message indexes: readers scan the file linearly. The only chunks are
the uncompressed one-channel chunks of `add_message_records` (the viewable
per-sample channels, tools/logs/viz_log.py). The mcap package reads these files
back (tests/tools/test_mcap_log.py).

`LibraryMcap` puts the `mcap` package's Writer behind the same four calls,
for compressed (chunked) logs.
"""

from __future__ import annotations

import os
import struct
import zlib

from mcap.writer import CompressionType, Writer

MAGIC = b"\x89MCAP0\r\n"

OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = \
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06
OP_STATISTICS, OP_METADATA, OP_METADATA_INDEX, OP_SUMMARY_OFFSET, OP_DATA_END = \
    0x0B, 0x0C, 0x0D, 0x0E, 0x0F

_RECORD = struct.Struct("<BQ")           # opcode, content length
_MESSAGE = struct.Struct("<BQHIQQ")      # record prefix + channel, sequence, log, publish time
# record prefix + message start/end time, uncompressed size and CRC (0: not computed),
# compression "" (length 0), records length
_CHUNK = struct.Struct("<BQQQQIIQ")


def _string(s: str) -> bytes:
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def _bytes(b: bytes) -> bytes:
    return struct.pack("<I", len(b)) + b


def _string_map(d: dict[str, str]) -> bytes:
    body = b"".join(_string(k) + _string(v) for k, v in d.items())
    return _bytes(body)


def _record(opcode: int, content: bytes) -> bytes:
    return _RECORD.pack(opcode, len(content)) + content


class McapFile:
    """Unchunked MCAP to a file path. Not thread-safe; finish() once."""

    def __init__(self, path, profile: str = "", library: str = ""):
        self._f = open(path, "wb", buffering=0)
        self._fd = self._f.fileno()
        self._pos = 0
        self._schemas: list[bytes] = []
        self._channels: list[bytes] = []
        self._metadata_index: list[tuple[int, int, str]] = []
        self._counts: dict[int, int] = {}
        self._messages = 0
        self._chunks = 0
        self._start_ns: int | None = None
        self._end_ns = 0
        self._write(MAGIC + _record(OP_HEADER, _string(profile) + _string(library)))

    def _write(self, data: bytes) -> None:
        self._write_all(data)
        self._pos += len(data)

    def _write_all(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self._fd, view):]

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        sid = len(self._schemas) + 1
        rec = _record(OP_SCHEMA, struct.pack("<H", sid) + _string(name) + _string(encoding)
                      + _bytes(data))
        self._schemas.append(rec)
        self._write(rec)
        return sid

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str] | None = None) -> int:
        cid = len(self._channels) + 1
        rec = _record(OP_CHANNEL, struct.pack("<HH", cid, schema_id) + _string(topic)
                      + _string(message_encoding) + _string_map(metadata or {}))
        self._channels.append(rec)
        self._counts[cid] = 0
        self._write(rec)
        return cid

    def add_message(self, channel_id: int, log_time: int, publish_time: int, sequence: int,
                    parts: list) -> None:
        """One Message record whose data is the concatenation of `parts` (bytes-like)."""
        size = sum(len(p) for p in parts)
        head = _MESSAGE.pack(OP_MESSAGE, 22 + size, channel_id, sequence, log_time, publish_time)
        total = len(head) + size
        written = os.writev(self._fd, [head, *parts])
        if written != total:  # a short write (rare, large records): finish it by hand
            self._write_all(b"".join([head, *[bytes(p) for p in parts]])[written:])
        self._pos += total
        self._counts[channel_id] += 1
        self._messages += 1
        self._start_ns = log_time if self._start_ns is None else min(self._start_ns, log_time)
        self._end_ns = max(self._end_ns, log_time)

    def add_message_records(self, channel_id: int, records, count: int, start_ns: int,
                            end_ns: int) -> None:
        """`count` complete Message records of one channel (tools/logs/viz_codec.py builds them
        in bulk) as one uncompressed Chunk, in one write. Readers that want other
        channels skip the chunk without parsing it (tools/logs/log_reader.py); no chunk
        index is written, so every reader scans the file and sees both kinds."""
        size = len(records)
        head = _CHUNK.pack(OP_CHUNK, 8 + 8 + 8 + 4 + 4 + 8 + size, start_ns, end_ns, size, 0,
                           0, size)
        written = os.writev(self._fd, [head, records])
        if written != len(head) + size:
            self._write_all(b"".join([head, bytes(records)])[written:])
        self._pos += len(head) + size
        self._counts[channel_id] += count
        self._messages += count
        self._chunks += 1
        self._start_ns = start_ns if self._start_ns is None else min(self._start_ns, start_ns)
        self._end_ns = max(self._end_ns, end_ns)

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        rec = _record(OP_METADATA, _string(name) + _string_map(data))
        self._metadata_index.append((self._pos, len(rec), name))
        self._write(rec)

    def finish(self) -> None:
        self._write(_record(OP_DATA_END, struct.pack("<I", 0)))
        summary_start = self._pos
        groups: list[tuple[int, bytes]] = [
            (OP_SCHEMA, b"".join(self._schemas)),
            (OP_CHANNEL, b"".join(self._channels)),
            (OP_STATISTICS, _record(OP_STATISTICS, self._statistics())),
            (OP_METADATA_INDEX, b"".join(
                _record(OP_METADATA_INDEX, struct.pack("<QQ", off, length) + _string(name))
                for off, length, name in self._metadata_index)),
        ]
        summary = b""
        offsets = b""
        for opcode, data in groups:
            if data:
                offsets += _record(OP_SUMMARY_OFFSET, struct.pack(
                    "<BQQ", opcode, summary_start + len(summary), len(data)))
                summary += data
        offset_start = summary_start + len(summary)
        summary += offsets
        footer_head = struct.pack("<BQQQ", OP_FOOTER, 20, summary_start, offset_start)
        crc = zlib.crc32(footer_head, zlib.crc32(summary))
        self._write(summary + footer_head + struct.pack("<I", crc) + MAGIC)
        self._f.close()

    def close(self) -> None:
        """Close without a summary (the file then reads as cut short)."""
        if not self._f.closed:
            self._f.close()

    def _statistics(self) -> bytes:
        counts = b"".join(struct.pack("<HQ", cid, n) for cid, n in self._counts.items())
        return struct.pack("<QHIIIIQQ", self._messages, len(self._schemas), len(self._channels),
                           0, len(self._metadata_index), self._chunks, self._start_ns or 0,
                           self._end_ns) + _bytes(counts)


class LibraryMcap:
    """The mcap package's chunked, compressed Writer behind McapFile's calls."""

    def __init__(self, path, compression: str, chunk_bytes: int, profile: str = "",
                 library: str = ""):
        kind = {"lz4": CompressionType.LZ4, "zstd": CompressionType.ZSTD}[compression]
        self._f = open(path, "wb")
        self._w = Writer(self._f, chunk_size=chunk_bytes, compression=kind)
        self._w.start(profile=profile, library=library)
        self.register_schema = self._w.register_schema
        self.register_channel = self._w.register_channel
        self.add_metadata = self._w.add_metadata

    def add_message(self, channel_id: int, log_time: int, publish_time: int, sequence: int,
                    parts: list) -> None:
        self._w.add_message(channel_id, log_time=log_time, publish_time=publish_time,
                            sequence=sequence, data=b"".join(parts))

    def finish(self) -> None:
        self._w.finish()
        self._f.close()

    def close(self) -> None:
        if not self._f.closed:
            self._f.close()


class NullMcap:
    """McapFile's calls, writing nothing: a live view without a log file (tools/logs/live_view.py)
    still runs the writer's batching, which feeds the viewable channels."""

    def __init__(self):
        self._ids = 0

    def _next(self, *_args, **_kw) -> int:
        self._ids += 1
        return self._ids

    register_schema = register_channel = _next

    def add_message(self, *_args) -> None:
        pass

    add_message_records = add_metadata = add_message

    def finish(self) -> None:
        pass

    close = finish
