"""tools/logs/mcap_layout.py against the mcap package's own record encoder: the same bytes for
every record our writers build, and the viewable channels' numpy rows are those records."""

import zlib

import numpy as np
import pytest
from mcap import records as R
from mcap.data_stream import RecordBuilder

from silbridge.tools.logs import mcap_layout as L
from silbridge.tools.logs.viz_codec import FixedMessage, cdr_items


def _library(record) -> bytes:
    b = RecordBuilder()
    record.write(b)
    return b.end()


_MESSAGES = L.message_records(7, 2**32 - 1, [11, 2**40], [b"abc", bytes(range(40))])

CASES = {
    "header": (L.header_record("prof", "silbridge-log/1"),
               R.Header(profile="prof", library="silbridge-log/1")),
    "schema": (L.schema_record(3, "pkg/msg/X", "ros2msg", b"float64 x\n"),
               R.Schema(id=3, name="pkg/msg/X", encoding="ros2msg", data=b"float64 x\n")),
    "channel": (L.channel_record(2, 3, "/imu", "cdr", {"silbridge.dtype": "[]", "k": "v"}),
                R.Channel(id=2, schema_id=3, topic="/imu", message_encoding="cdr",
                          metadata={"silbridge.dtype": "[]", "k": "v"})),
    # the sequence wraps at 2**32 as the u32 field does
    "messages": (_MESSAGES,
                 _library(R.Message(channel_id=7, sequence=2**32 - 1, log_time=11,
                                    publish_time=11, data=b"abc"))
                 + _library(R.Message(channel_id=7, sequence=0, log_time=2**40,
                                      publish_time=2**40, data=bytes(range(40))))),
    "chunk": (L.CHUNK_HEAD.pack(L.OP_CHUNK, L.CHUNK_FIXED + len(_MESSAGES), 11, 2**40,
                                len(_MESSAGES), 0, 0, len(_MESSAGES)) + _MESSAGES,
              R.Chunk(compression="", data=_MESSAGES, message_start_time=11,
                      message_end_time=2**40, uncompressed_crc=0,
                      uncompressed_size=len(_MESSAGES))),
    "metadata": (L.metadata_record("silbridge.run", {"json": "{}"}),
                 R.Metadata(name="silbridge.run", metadata={"json": "{}"})),
    "data_end": (L.data_end_record(), R.DataEnd(data_section_crc=0)),
    "statistics": (L.statistics_record(9, 2, 3, 1, 4, 5, 6, {1: 4, 2: 5}),
                   R.Statistics(message_count=9, schema_count=2, channel_count=3,
                                attachment_count=0, metadata_count=1, chunk_count=4,
                                message_start_time=5, message_end_time=6,
                                channel_message_counts={1: 4, 2: 5})),
    "metadata_index": (L.metadata_index_record(100, 20, "silbridge.end"),
                       R.MetadataIndex(offset=100, length=20, name="silbridge.end")),
    "summary_offset": (L.summary_offset_record(L.OP_CHANNEL, 300, 40),
                       R.SummaryOffset(group_opcode=L.OP_CHANNEL, group_start=300,
                                       group_length=40)),
    "footer": (L.footer_and_magic(1000, 1200, b"summary bytes")[:-len(L.MAGIC)],
               R.Footer(summary_start=1000, summary_offset_start=1200, summary_crc=zlib.crc32(
                   L.RECORD_PREFIX.pack(L.OP_FOOTER, 20) + (1000).to_bytes(8, "little")
                   + (1200).to_bytes(8, "little"), zlib.crc32(b"summary bytes")))),
}


@pytest.mark.parametrize("name", CASES)
def test_records_are_the_mcap_packages_bytes(name):
    ours, library = CASES[name]
    assert ours == (library if isinstance(library, bytes) else _library(library))


def test_split_gives_back_what_message_records_packed():
    assert L.split_message_records(_MESSAGES) == [(7, 2**32 - 1, 11, 11, b"abc"),
                                                  (7, 0, 2**40, 2**40, bytes(range(40)))]
    with pytest.raises(ValueError, match="not a Message"):
        L.split_message_records(L.data_end_record())


def test_viewable_rows_are_message_records():
    """viz_codec's numpy rows use the layout's head: each row is a Message record."""
    fixed = FixedMessage(cdr_items(["x_m"]))
    recs = fixed.encode(4, 10, np.array([1_500_000_000, 2_000_000_001]), {"x_m": [1.0, -2.0]})
    split = L.split_message_records(recs.tobytes())
    assert [(c, s, t, p) for c, s, t, p, _ in split] == [
        (4, 10, 1_500_000_000, 1_500_000_000), (4, 11, 2_000_000_001, 2_000_000_001)]
    assert [d for *_, d in split] == [bytes(d) for d in fixed.data_of(recs)]
