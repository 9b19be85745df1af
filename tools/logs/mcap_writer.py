"""Where a run log's MCAP bytes go: our unchunked writer, the mcap package's, or nowhere.

Three classes behind the same calls (`McapSink`); `LogWriter` (tools/logs/mcap_log.py)
picks one at construction from its `compression` argument:

- `McapFile` (compression "none", the default and what every `--log` run writes): our own
  writer, on the loop's path. The `mcap` package's Writer builds every record in a BytesIO,
  copies it out and then writes it: three copies of each batch message, about half a
  microsecond per physics step of a logged run (tools/logs/log_bench.py). Here a message
  record is one os.writev() of its header and the caller's buffers, gathered by the kernel,
  and every record is in the file when the call returns (a killed run keeps it).
- `LibraryMcap` (compression "lz4" or "zstd", `LogWriter`'s public option and
  `log_bench --compression`): the mcap package's Writer, because compressed chunks need its
  chunk builder and its lz4/zstd codecs, which we do not write again. Not on any flight's
  path: its per-message copies cost nothing that matters when compressing costs more.
- `NullMcap`: a live view without a log file.

So production needs both writers, for different files (unchunked vs compressed chunks);
neither is a reference for the other. What checks McapFile's bytes is the mcap package's
reader (tests/tools/test_mcap_log.py, tests/tools/test_viz_log.py).

What McapFile writes (the bytes themselves: tools/logs/mcap_layout.py): magic, Header, then
Schema, Channel, Message and Metadata records in call order; on finish, DataEnd and a summary
section (schemas, channels, Statistics, MetadataIndex records and their SummaryOffsets), the
Footer (summary CRC included) and the magic. No chunk or message indexes: readers scan the
file linearly. The only chunks are the uncompressed one-channel chunks of
`add_message_records` (the viewable per-sample channels, tools/logs/viz_log.py).
"""

from __future__ import annotations

import os
from typing import Protocol

from mcap.writer import CompressionType, Writer

from silbridge.tools.logs.mcap_layout import (CHUNK_FIXED, CHUNK_HEAD, DATA_END_BYTES,
                                              FOOTER_BYTES, MAGIC, MESSAGE_FIXED,
                                              MESSAGE_HEAD, OP_CHANNEL, OP_CHUNK, OP_DATA_END,
                                              OP_METADATA_INDEX, OP_MESSAGE, OP_SCHEMA,
                                              OP_STATISTICS, channel_record, data_end_record,
                                              footer_and_magic, header_record,
                                              metadata_index_record, metadata_record,
                                              read_footer,
                                              schema_record, split_message_records,
                                              statistics_record, summary_offset_record)


class McapSink(Protocol):
    """The calls LogWriter and the viewable channels make, whichever writer is behind them."""

    def register_schema(self, name: str, encoding: str, data: bytes) -> int: ...

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str] | None = None) -> int: ...

    def add_message(self, channel_id: int, log_time: int, publish_time: int, sequence: int,
                    parts: list) -> None: ...

    def add_message_records(self, channel_id: int, records, count: int, start_ns: int,
                            end_ns: int) -> None: ...

    def add_metadata(self, name: str, data: dict[str, str]) -> None: ...

    def finish(self) -> None: ...

    def close(self) -> None: ...


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
        self._write(MAGIC + header_record(profile, library))

    def _write(self, data: bytes) -> None:
        self._write_all(data)
        self._pos += len(data)

    def _write_all(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self._fd, view):]

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        sid = len(self._schemas) + 1
        rec = schema_record(sid, name, encoding, data)
        self._schemas.append(rec)
        self._write(rec)
        return sid

    def register_channel(self, topic: str, message_encoding: str, schema_id: int,
                         metadata: dict[str, str] | None = None) -> int:
        cid = len(self._channels) + 1
        rec = channel_record(cid, schema_id, topic, message_encoding, metadata or {})
        self._channels.append(rec)
        self._counts[cid] = 0
        self._write(rec)
        return cid

    def add_message(self, channel_id: int, log_time: int, publish_time: int, sequence: int,
                    parts: list) -> None:
        """One Message record whose data is the concatenation of `parts` (bytes-like)."""
        size = sum(len(p) for p in parts)
        head = MESSAGE_HEAD.pack(OP_MESSAGE, MESSAGE_FIXED + size, channel_id, sequence, log_time,
                                 publish_time)
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
        head = CHUNK_HEAD.pack(OP_CHUNK, CHUNK_FIXED + size, start_ns, end_ns, size, 0, 0, size)
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
        rec = metadata_record(name, data)
        self._metadata_index.append((self._pos, len(rec), name))
        self._write(rec)

    def finish(self) -> None:
        self._write(data_end_record())
        summary_start = self._pos
        groups: list[tuple[int, bytes]] = [
            (OP_SCHEMA, b"".join(self._schemas)),
            (OP_CHANNEL, b"".join(self._channels)),
            (OP_STATISTICS, statistics_record(
                self._messages, len(self._schemas), len(self._channels),
                len(self._metadata_index), self._chunks, self._start_ns or 0, self._end_ns,
                self._counts)),
            (OP_METADATA_INDEX, b"".join(metadata_index_record(off, length, name)
                                         for off, length, name in self._metadata_index)),
        ]
        summary = b""
        offsets = b""
        for opcode, data in groups:
            if data:
                offsets += summary_offset_record(opcode, summary_start + len(summary), len(data))
                summary += data
        offset_start = summary_start + len(summary)
        summary += offsets
        self._write(summary + footer_and_magic(summary_start, offset_start, summary))
        self._f.close()

    def close(self) -> None:
        """Close without a summary (the file then reads as cut short)."""
        if not self._f.closed:
            self._f.close()

    @classmethod
    def reopen(cls, path) -> "McapFile":
        """A finished file of ours, opened to write more records after its data: the summary,
        footer and DataEnd are cut off and finish() writes them again, with what was there
        plus what came since. For channels only one process can produce after another
        process wrote the log (tools/logs/rotor_log.py: the bridge's /rotor of a
        two-process flight). ValueError for a file without our footer (cut, compressed)."""
        from mcap.reader import make_reader
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            size = fh.tell()
            if size < len(MAGIC) + FOOTER_BYTES:
                raise ValueError("too short for a finished MCAP file")
            fh.seek(size - FOOTER_BYTES)
            data_end = read_footer(fh.read(FOOTER_BYTES)) - DATA_END_BYTES
            fh.seek(data_end)
            if fh.read(1) != bytes([OP_DATA_END]):
                raise ValueError("no DataEnd record before the summary")
            fh.seek(0)
            summary = make_reader(fh).get_summary()
        if summary is None or summary.statistics is None or summary.chunk_indexes:
            raise ValueError("not an unchunked file with statistics (McapFile writes those)")
        self = cls.__new__(cls)
        self._f = open(path, "r+b", buffering=0)
        self._f.truncate(data_end)
        self._f.seek(data_end)
        self._fd = self._f.fileno()
        self._pos = data_end
        # Ids count up from 1 in call order (register_*), so the records keep their ids.
        self._schemas = [schema_record(s.id, s.name, s.encoding, s.data)
                         for s in sorted(summary.schemas.values(), key=lambda s: s.id)]
        chans = sorted(summary.channels.values(), key=lambda c: c.id)
        self._channels = [channel_record(c.id, c.schema_id, c.topic, c.message_encoding,
                                         c.metadata) for c in chans]
        st = summary.statistics
        self._counts = {c.id: st.channel_message_counts.get(c.id, 0) for c in chans}
        self._metadata_index = [(m.offset, m.length, m.name) for m in summary.metadata_indexes]
        self._messages, self._chunks = st.message_count, st.chunk_count
        self._start_ns, self._end_ns = st.message_start_time, st.message_end_time
        return self


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

    def add_message_records(self, channel_id: int, records, count: int, start_ns: int,
                            end_ns: int) -> None:
        """McapFile's ready Message records, handed to the library one message at a time
        (it builds its own records, inside its compressed chunks)."""
        for channel, sequence, log_time, publish_time, data in split_message_records(records):
            self._w.add_message(channel, log_time=log_time, publish_time=publish_time,
                                sequence=sequence, data=data)

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
