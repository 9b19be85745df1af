"""The MCAP byte layout (mcap.dev/spec), in one place: every record silbridge writes itself.

Writers built on it: tools/logs/mcap_writer.py (`McapFile`, a whole unchunked file),
tools/logs/viz_codec.py (the viewable channels' fixed-size Message records, a batch at a time
as numpy rows of `MESSAGE_HEAD_FIELDS`) and tools/logs/viz_log.py (variable-size messages,
`message_records`). tools/logs/log_reader.py walks the records by these prefixes, takes each
Message record's data where it lies and peeks at a chunk's first record to skip it unread;
the other records it reads go through the mcap package, which is also what checks these
bytes (tests/tools/test_mcap_log.py).

Layout rules used throughout: little-endian fixed widths; a record is an opcode byte, a u64
length of what follows, then its fields; a string or byte array is a u32 length then the
bytes; a map is a u32 byte length then its key/value pairs.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

MAGIC = b"\x89MCAP0\r\n"

OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = \
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06
OP_STATISTICS, OP_METADATA, OP_METADATA_INDEX, OP_SUMMARY_OFFSET, OP_DATA_END = \
    0x0B, 0x0C, 0x0D, 0x0E, 0x0F

RECORD_PREFIX = struct.Struct("<BQ")     # opcode, length of the content after it

# A Message record up to its data: the prefix, channel id, sequence, log and publish time [ns].
# Declared once as numpy fields (viz_codec builds whole batches of records as array rows);
# the struct below is derived from them.
MESSAGE_HEAD_FIELDS = [("op", "u1"), ("length", "<u8"), ("channel", "<u2"),
                       ("sequence", "<u4"), ("log_time", "<u8"), ("publish_time", "<u8")]
MESSAGE_HEAD_DTYPE = np.dtype(MESSAGE_HEAD_FIELDS)          # packed: a row is the bytes
_STRUCT_CODE = {"u1": "B", "u2": "H", "u4": "I", "u8": "Q"}
MESSAGE_HEAD = struct.Struct("<" + "".join(
    _STRUCT_CODE[f"{np.dtype(t).kind}{np.dtype(t).itemsize}"] for _, t in MESSAGE_HEAD_FIELDS))
assert MESSAGE_HEAD.size == MESSAGE_HEAD_DTYPE.itemsize
MESSAGE_FIXED = MESSAGE_HEAD.size - RECORD_PREFIX.size       # content bytes before the data
_CHANNEL_AT = MESSAGE_HEAD_DTYPE.fields["channel"][1]
MESSAGE_CHANNEL = slice(_CHANNEL_AT, _CHANNEL_AT + MESSAGE_HEAD_DTYPE["channel"].itemsize)

# A Chunk record up to its records: the prefix, message start and end time, uncompressed
# size, uncompressed CRC (0: not computed), compression "" (a zero length), records length.
CHUNK_HEAD = struct.Struct("<BQQQQIIQ")
CHUNK_FIXED = CHUNK_HEAD.size - RECORD_PREFIX.size

U16 = struct.Struct("<H")
_U32 = struct.Struct("<I")
_STATISTICS = struct.Struct("<QHIIIIQQ")  # messages, schemas, channels, attachments,
#                                           metadata, chunks, message start, message end
_CHANNEL_COUNT = struct.Struct("<HQ")     # one entry of Statistics' per-channel map
_METADATA_INDEX = struct.Struct("<QQ")    # offset, length (then the name)
_SUMMARY_OFFSET = struct.Struct("<BQQ")   # group opcode, group start, group length
_FOOTER_HEAD = struct.Struct("<BQQQ")     # opcode, length, summary start, offsets start
_FOOTER_LENGTH = 8 + 8 + 4                # the two offsets and the summary CRC


def string(s: str) -> bytes:
    return prefixed(s.encode())


def prefixed(b: bytes) -> bytes:
    """A byte array: u32 length, then the bytes."""
    return _U32.pack(len(b)) + b


def string_map(d: dict[str, str]) -> bytes:
    return prefixed(b"".join(string(k) + string(v) for k, v in d.items()))


def record(opcode: int, content: bytes) -> bytes:
    return RECORD_PREFIX.pack(opcode, len(content)) + content


def header_record(profile: str, library: str) -> bytes:
    return record(OP_HEADER, string(profile) + string(library))


def schema_record(schema_id: int, name: str, encoding: str, data: bytes) -> bytes:
    return record(OP_SCHEMA, U16.pack(schema_id) + string(name) + string(encoding)
                  + prefixed(data))


def channel_record(channel_id: int, schema_id: int, topic: str, message_encoding: str,
                   metadata: dict[str, str]) -> bytes:
    return record(OP_CHANNEL, U16.pack(channel_id) + U16.pack(schema_id) + string(topic)
                  + string(message_encoding) + string_map(metadata))


def message_records(channel_id: int, first_sequence: int, times_ns: list, datas: list) -> bytes:
    """Message records of one channel (log time = publish time), sequence numbers counting
    up from first_sequence and wrapping at 2**32 as the field does."""
    return b"".join(MESSAGE_HEAD.pack(OP_MESSAGE, MESSAGE_FIXED + len(d), channel_id,
                                      (first_sequence + i) & 0xFFFFFFFF, ns, ns) + d
                    for i, (ns, d) in enumerate(zip(times_ns, datas)))


def split_message_records(raw) -> list[tuple[int, int, int, int, bytes]]:
    """Back from concatenated Message records to (channel, sequence, log time, publish
    time, data) each: for a writer that builds its own records (the mcap package's)."""
    view, pos, out = memoryview(raw), 0, []
    while pos < len(view):
        if view[pos] != OP_MESSAGE:
            raise ValueError(f"record at byte {pos} has opcode {view[pos]:#04x}, not a Message")
        _, length, channel, sequence, log_time, publish_time = \
            MESSAGE_HEAD.unpack_from(view, pos)
        end = pos + RECORD_PREFIX.size + length
        out.append((channel, sequence, log_time, publish_time,
                    bytes(view[pos + MESSAGE_HEAD.size:end])))
        pos = end
    return out


def metadata_record(name: str, data: dict[str, str]) -> bytes:
    return record(OP_METADATA, string(name) + string_map(data))


def data_end_record() -> bytes:
    return record(OP_DATA_END, _U32.pack(0))        # data section CRC 0: not computed


def statistics_record(messages: int, schemas: int, channels: int, metadata: int, chunks: int,
                      start_ns: int, end_ns: int, channel_counts: dict[int, int]) -> bytes:
    counts = b"".join(_CHANNEL_COUNT.pack(cid, n) for cid, n in channel_counts.items())
    return record(OP_STATISTICS, _STATISTICS.pack(messages, schemas, channels, 0, metadata,
                                                  chunks, start_ns, end_ns) + prefixed(counts))


def metadata_index_record(offset: int, length: int, name: str) -> bytes:
    return record(OP_METADATA_INDEX, _METADATA_INDEX.pack(offset, length) + string(name))


def summary_offset_record(opcode: int, start: int, length: int) -> bytes:
    return record(OP_SUMMARY_OFFSET, _SUMMARY_OFFSET.pack(opcode, start, length))


def footer_and_magic(summary_start: int, offsets_start: int, summary: bytes) -> bytes:
    """The Footer (its CRC covers the summary section and the footer up to the CRC), then
    the closing magic."""
    head = _FOOTER_HEAD.pack(OP_FOOTER, _FOOTER_LENGTH, summary_start, offsets_start)
    return head + _U32.pack(zlib.crc32(head, zlib.crc32(summary))) + MAGIC


# The end of a finished file: Footer (head and summary CRC) and the closing magic.
FOOTER_BYTES = _FOOTER_HEAD.size + 4 + len(MAGIC)
DATA_END_BYTES = RECORD_PREFIX.size + 4   # DataEnd: prefix and its CRC


def read_footer(tail: bytes) -> int:
    """Where the summary section starts, from a finished file's last FOOTER_BYTES bytes
    (ValueError if they are not a Footer and the magic: a cut or foreign file)."""
    op, length, summary_start, _offsets = _FOOTER_HEAD.unpack_from(tail)
    if len(tail) != FOOTER_BYTES or op != OP_FOOTER or length != _FOOTER_LENGTH \
            or tail[-len(MAGIC):] != MAGIC:
        raise ValueError("no MCAP footer at the end of the file")
    return summary_start
