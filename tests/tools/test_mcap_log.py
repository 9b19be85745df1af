"""MCAP run logs: exact round trip, Foxglove-readable schemas, cut and corrupt files."""

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader

from silbridge.shm.records import RECORD_DTYPE, Kind, empty
from silbridge.tools.logs.log_format import CHANNEL_DTYPE_KEY
from silbridge.tools.logs.log_synth import SYNTH_STATUS_DTYPE, synthetic_run, write_run
from silbridge.tools.logs.mcap_layout import MAGIC, OP_MESSAGE, RECORD_PREFIX
from silbridge.tools.logs.mcap_log import TIMING_DTYPE, LogError, LogWriter, read_log


@pytest.fixture(scope="module")
def run():
    return synthetic_run(3.0, seed=3)


def _same_rows(got: np.ndarray, want: np.ndarray) -> None:
    assert len(got) == len(want)
    for name in got.dtype.names:
        assert got.dtype.fields[name][0].shape == want.dtype.fields[name][0].shape, name
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)


def test_round_trip_keeps_every_field_and_shape(tmp_path, run):
    path = tmp_path / "run.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=100) as w:
        write_run(run, w)
    log = read_log(path)
    assert not log.truncated and log.read_error is None and not log.corrupt
    assert set(log.channels) == set(run.channels)
    for name, want in run.channels.items():
        _same_rows(log.channels[name], want)
    # Padding and reserved words are not logged; everything else is.
    imu = log.channels["/imu"]
    assert "_pad" not in imu.dtype.names and "reserved" not in imu.dtype.names
    assert imu.dtype["accel_frd_m_s2"].shape == (3,)
    assert log.channels["/fc/status"].dtype["q_est_wxyz"].shape == (4,)
    assert "reserved0" not in log.channels["/pwm"].dtype.names
    assert log.metadata["config"]["imu_hz"] == 1000.0
    assert log.metadata["params"]["ATC_RAT_RLL_D"] == 0.0036
    assert [e["kind"] for e in log.events] == ["mode", "param", "disturbance", "check"]
    assert log.events[1]["fields"] == {"name": "ATC_RAT_RLL_D", "value": 0.004}
    assert log.end["rows"]["/imu"] == len(run.channels["/imu"])


def test_summary_and_index_read_by_the_mcap_package(tmp_path, run):
    """The hand-written summary (statistics, metadata index) parses and points right."""
    path = tmp_path / "summary.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=1000) as w:
        write_run(run, w)
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        stats = summary.statistics
        topics = {c.id: c.topic for c in summary.channels.values()}
        counts = {topics[cid]: n for cid, n in stats.channel_message_counts.items()}
        assert counts["/imu"] == 3 and counts["/fc/status"] == 2 and counts["/events"] == 4
        assert stats.message_count == sum(counts.values())
        assert stats.message_end_time == 3_000_000_000
        assert [m.name for m in reader.iter_metadata()] == ["silbridge.run", "silbridge.end"]
        assert reader.get_header().library.startswith("silbridge-log/")


def test_row_by_row_writes_equal_bulk_writes(tmp_path):
    rows = np.zeros(1000, dtype=SYNTH_STATUS_DTYPE)
    rows["sim_ns"] = np.arange(1000) * 2_500_000
    rows["motor_us"] = np.arange(4000, dtype=np.float32).reshape(1000, 4)
    rows["limited"] = np.arange(3000).reshape(1000, 3) % 2
    path = tmp_path / "rows.mcap"
    with LogWriter(path, metadata={}, batch_rows=64) as w:
        for i in range(0, 1000, 7):  # uneven pieces across batch boundaries
            w.write("/fc/status", rows[i:i + 7])
    _same_rows(read_log(path).channels["/fc/status"], rows)


def test_packed_dtype_is_relaid_out_and_read_back(tmp_path):
    packed = np.dtype([("flag", "u1"), ("sim_ns", "<i8"), ("v", "<f4", (2, 3)), ("ok", "?")])
    assert packed.itemsize == 34  # no alignment: CDR cannot carry it byte for byte
    rows = np.zeros(700, packed)
    rows["sim_ns"] = np.arange(700) * 1000
    rows["flag"] = np.arange(700) % 251
    rows["v"] = np.arange(4200, dtype=np.float32).reshape(700, 2, 3)
    rows["ok"] = np.arange(700) % 3 == 0
    path = tmp_path / "packed.mcap"
    with LogWriter(path, metadata={}, batch_rows=256) as w:
        w.write("/custom", rows)
    got = read_log(path).channels["/custom"]
    assert got.dtype.itemsize == 48 and got.dtype["v"].shape == (2, 3)  # C alignment
    _same_rows(got, rows)


def test_mixed_records_split_by_kind(tmp_path, run):
    mixed = np.concatenate([run.channels[c].view(RECORD_DTYPE)
                            for c in ("/imu", "/gt_att", "/baro", "/pwm")])
    order = np.argsort(mixed["sim_ns"], kind="stable")
    path = tmp_path / "mixed.mcap"
    with LogWriter(path, metadata={}, batch_rows=128) as w:
        for i in range(0, len(mixed), 5):
            w.write_records(mixed[order][i:i + 5])
        assert w.rows_written["/imu"] == len(run.channels["/imu"])
    log = read_log(path)
    for c in ("/imu", "/gt_att", "/baro", "/pwm"):
        _same_rows(log.channels[c], run.channels[c])


def test_unknown_record_kinds_are_counted_not_logged(tmp_path, run):
    recs = run.channels["/imu"][:10].view(RECORD_DTYPE).copy()
    recs["kind"][3] = 0
    path = tmp_path / "unknown.mcap"
    with LogWriter(path, metadata={}) as w:
        w.write_records(recs)
    log = read_log(path)
    assert len(log.channels["/imu"]) == 9
    assert log.end["unknown_records"] == {"0": 1}
    from silbridge.tools.logs.integrity import check_log
    assert any("1 records of unknown kind 0" in p for p in check_log(log))


def test_reading_some_channels_only(tmp_path, run):
    path = tmp_path / "some.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    log = read_log(path, channels=["/pwm"])
    assert list(log.channels) == ["/pwm"] and len(log.events) == 4


def test_write_cycle_equals_the_separate_calls(tmp_path, run):
    from silbridge.tools.logs.log_synth import step_slices
    paths = [tmp_path / "cycle.mcap", tmp_path / "separate.mcap"]
    steps = step_slices(run)[:1500]
    for path in paths:
        with LogWriter(path, metadata={}, batch_rows=128) as w:
            for s in steps:
                recs = np.concatenate([s[c].view(RECORD_DTYPE) for c in ("/imu", "/gt_att")])
                timing = tuple(int(v) for v in s["/timing"][0])
                if path.name == "cycle.mcap":
                    w.write_cycle(recs, s["/fc/status"], timing, s["/pwm"])
                else:
                    w.write_records(recs)
                    w.write("/fc/status", s["/fc/status"])
                    w.declare("/timing", TIMING_DTYPE)
                    w.pack("/timing", *timing)
                    w.write_records(s["/pwm"])
    a, b = (read_log(p) for p in paths)
    assert set(a.channels) == set(b.channels) == {"/imu", "/gt_att", "/pwm", "/fc/status",
                                                   "/timing"}
    for name in a.channels:
        _same_rows(a.channels[name], b.channels[name])
    assert len(a.channels["/timing"]) == 1500


def test_pack_builds_timing_rows(tmp_path):
    path = tmp_path / "timing.mcap"
    with LogWriter(path, metadata={}, batch_rows=10) as w:
        w.declare("/timing", TIMING_DTYPE)
        for k in range(25):
            w.pack("/timing", k * 1000, 10 * k, 10 * k + 3, 0 if k % 3 else 10 * k + 7, 5)
    tim = read_log(path).channels["/timing"]
    assert tim.dtype == TIMING_DTYPE
    np.testing.assert_array_equal(tim["consume_wall_ns"], 10 * np.arange(25) + 3)
    np.testing.assert_array_equal(tim["pwm_wall_ns"][:4], [7, 0, 0, 37])


@pytest.mark.parametrize("compression", ["lz4", "zstd"])
def test_compressed_logs_round_trip(tmp_path, run, compression):
    path = tmp_path / f"{compression}.mcap"
    with LogWriter(path, metadata=run.metadata, compression=compression) as w:
        write_run(run, w)
    log = read_log(path)
    assert not log.truncated
    _same_rows(log.channels["/fc/status"], run.channels["/fc/status"])
    # The rows came back through compressed chunks: every data message sits in a chunk of
    # the asked compression, and the chunks are smaller than what they hold.
    with open(path, "rb") as f:
        records = list(StreamReader(f, skip_magic=False, emit_chunks=True).records)
    chunks = [r for r in records if isinstance(r, Chunk)]
    assert chunks and all(c.compression == compression for c in chunks)
    assert sum(len(c.data) for c in chunks) < sum(c.uncompressed_size for c in chunks)
    assert not any(isinstance(r, Message) for r in records)     # none outside a chunk


def test_compressed_logs_hold_the_plain_logs_viewable_messages(tmp_path, run):
    """The viewable channels' records, built by our layout (tools/logs/mcap_layout.py), reach
    the mcap package's compressing writer message for message: same sequence numbers,
    times and bytes as in our own unchunked file."""
    got = {}
    for compression in ("none", "zstd"):
        path = tmp_path / f"{compression}.mcap"
        with LogWriter(path, metadata=run.metadata, compression=compression) as w:
            write_run(run, w)
        with open(path, "rb") as f:
            got[compression] = sorted(
                (c.topic, m.sequence, m.log_time, m.publish_time, m.data)
                for _, c, m in make_reader(f).iter_messages() if c.topic.startswith("/viz/"))
    assert {m[0] for m in got["none"]} >= {"/viz/attitude", "/viz/tf", "/viz/scene"}
    assert got["zstd"] == got["none"]


def test_a_channel_keeps_its_dtype(tmp_path):
    with LogWriter(tmp_path / "x.mcap", metadata={}) as w:
        w.write("/imu", empty(Kind.IMU, 2))
        with pytest.raises(ValueError, match="one dtype"):
            w.write("/imu", empty(Kind.PWM, 2))
        with pytest.raises(ValueError, match="sim_ns"):
            w.write("/other", np.zeros(2, dtype=[("x", "<f4")]))


def test_files_decode_with_the_ros2_decoder(tmp_path, run):
    """What Foxglove sees: ros2msg schemas, CDR messages, an array of rows per batch."""
    from mcap_ros2.decoder import DecoderFactory
    path = tmp_path / "fox.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=500) as w:
        write_run(run, w)
    seen = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, _msg, decoded in reader.iter_decoded_messages(
                topics=["/imu", "/fc/status", "/gnss", "/timing"]):
            seen.setdefault(channel.topic, (schema, decoded))
    schema, imu = seen["/imu"]
    assert schema.encoding == "ros2msg" and schema.name == "silbridge_msgs/msg/ImuBatch"
    want = run.channels["/imu"]
    assert len(imu.rows) == len(imu.t_s) == 500 and imu.row_size == 64
    np.testing.assert_array_equal([r.accel_frd_m_s2[2] for r in imu.rows],
                                  want["accel_frd_m_s2"][:500, 2])
    np.testing.assert_array_equal([r.seq for r in imu.rows], want["seq"][:500])
    np.testing.assert_allclose(imu.t_s, want["sim_ns"][:500] * 1e-9)
    assert imu.stamp.sec == 0 and imu.stamp.nanosec == int(want["sim_ns"][0])
    _, st = seen["/fc/status"]
    np.testing.assert_array_equal([r.q_est_wxyz[3] for r in st.rows],
                                  run.channels["/fc/status"]["q_est_wxyz"][:500, 3])
    _, gnss = seen["/gnss"]
    assert [r.satellites for r in gnss.rows[:3]] == [12, 12, 12]
    _, tim = seen["/timing"]
    assert [r.consume_wall_ns for r in tim.rows[:5]] == \
        run.channels["/timing"]["consume_wall_ns"][:5].tolist()
    # Events are foxglove.Log JSON messages.
    with open(path, "rb") as f:
        msgs = list(make_reader(f).iter_messages(topics=["/events"]))
    schema, _, msg = msgs[0]
    assert schema.name == "foxglove.Log"
    assert json.loads(msg.data)["message"] == "takeoff"


def test_truncated_file_reads_up_to_the_cut(tmp_path, run):
    path = tmp_path / "whole.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=200) as w:
        write_run(run, w)
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 2 // 3])
    log = read_log(cut)
    assert log.truncated and "cut" in log.read_error and log.end is None
    assert log.metadata["config"]["duration_s"] == 3.0
    imu = log.channels["/imu"]
    assert 0 < len(imu) <= len(run.channels["/imu"])
    _same_rows(imu, run.channels["/imu"][: len(imu)])


def test_a_cut_anywhere_reads_a_prefix(tmp_path, run):
    """The scan walks the records by their lengths: a file cut inside a record's prefix,
    inside its fields or right after it (a killed writer, a copy stopped early) reads up
    to the cut and says so; never an exception, never a row that was not written."""
    path = tmp_path / "whole.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=200) as w:
        write_run(run, w)
    data = path.read_bytes()
    whole = read_log(path).channels
    # Cuts around the starts of three batch messages in the data section, byte by byte.
    starts, at = [], len(MAGIC)
    while at < len(data) // 2:
        op, length = RECORD_PREFIX.unpack_from(data, at)
        if op == OP_MESSAGE:
            starts.append(at)
        at += RECORD_PREFIX.size + length
    starts = starts[1:4]
    assert len(starts) == 3
    cut = tmp_path / "cut.mcap"
    for at in sorted({s + d for s in starts for d in range(-2, 40)}):
        cut.write_bytes(data[:at])
        log = read_log(cut)
        assert log.truncated and log.end is None and "cut at byte" in log.read_error, at
        for name, rows in log.channels.items():
            assert len(rows) <= len(whole[name])
            _same_rows(rows, whole[name][: len(rows)])


def test_a_file_that_cannot_be_mapped_is_read_whole(tmp_path, run, monkeypatch):
    import silbridge.tools.logs.log_reader as log_reader
    path = tmp_path / "whole.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=200) as w:
        write_run(run, w)
    mapped = read_log(path)

    def no_map(*_a, **_k):
        raise OSError("mmap: not on this file system")
    monkeypatch.setattr(log_reader.mmap, "mmap", no_map)
    read = read_log(path)
    assert read.read_error is None and read.events == mapped.events
    assert set(read.channels) == set(mapped.channels)
    for name, rows in mapped.channels.items():
        _same_rows(read.channels[name], rows)


def test_flipped_byte_is_caught_by_the_crc(tmp_path, run):
    path = tmp_path / "bad.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=200) as w:
        w.write("/imu", run.channels["/imu"])
    data = bytearray(path.read_bytes())
    first = read_log(path).channels["/imu"]
    # Flip one float byte in the middle of the IMU data (well inside a message body).
    pos = data.find(first["accel_frd_m_s2"][1500:1501, 0].tobytes())
    assert pos > 0
    data[pos] ^= 0xFF
    path.write_bytes(bytes(data))
    log = read_log(path)
    assert log.corrupt and "CRC" in log.read_error
    assert len(log.channels["/imu"]) < len(first)


def _batch_messages(path) -> list[tuple[str, bytes]]:
    """(topic, data) of every batch message of a log, in file order (the /viz channels'
    messages are not batches and carry no CRC)."""
    with open(path, "rb") as f:
        return [(c.topic, m.data) for _s, c, m in make_reader(f).iter_messages()
                if CHANNEL_DTYPE_KEY in c.metadata]


def test_every_batch_ends_with_zlibs_crc32_of_its_bytes(tmp_path, run):
    """The schema's crc32 field is zlib's CRC-32 (a reader in any language checks it with
    its zlib), whichever implementation computes it here."""
    import zlib
    path = tmp_path / "crc.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=150) as w:
        write_run(run, w)
    batches = _batch_messages(path)
    for i, (topic, data) in enumerate(batches):
        body, word = data[:-4], int.from_bytes(data[-4:], "little")
        assert word == zlib.crc32(body), (topic, i)
    assert len(batches) > 20


def test_without_fastcrc_logs_are_written_and_read_with_zlibs_crc(tmp_path, run):
    """`silbridge transport`'s -nofastcrc children hide fastcrc from the whole process: a
    log still works there, byte for byte the one written with fastcrc."""
    with LogWriter(tmp_path / "fast.mcap", metadata=run.metadata, batch_rows=150) as w:
        w.write("/imu", run.channels["/imu"])
    script = (
        "import sys; sys.modules['fastcrc'] = None\n"
        "from silbridge.tools.logs.log_synth import synthetic_run\n"
        "from silbridge.tools.logs.mcap_log import LogWriter, read_log\n"
        "run = synthetic_run(3.0, seed=3)\n"
        f"with LogWriter({str(tmp_path / 'zlib.mcap')!r}, metadata=run.metadata,"
        " batch_rows=150) as w:\n"
        "    w.write('/imu', run.channels['/imu'])\n"
        f"log = read_log({str(tmp_path / 'fast.mcap')!r})\n"
        "assert log.read_error is None and len(log.channels['/imu']) == len(run.channels['/imu'])\n"
        "import silbridge.tools.logs.log_schema as s; assert s.crc32.__module__ == 'zlib'\n")
    subprocess.run([sys.executable, "-c", script], check=True)
    ours, theirs = read_log(tmp_path / "fast.mcap"), read_log(tmp_path / "zlib.mcap")
    assert theirs.read_error is None
    _same_rows(theirs.channels["/imu"], ours.channels["/imu"])
    assert _batch_messages(tmp_path / "zlib.mcap") == _batch_messages(tmp_path / "fast.mcap")


def test_not_an_mcap_file_is_refused(tmp_path):
    bad = tmp_path / "notes.mcap"
    bad.write_text("hello")
    with pytest.raises(LogError, match="not an MCAP file"):
        read_log(bad)
    with pytest.raises(LogError, match="cannot read"):
        read_log(tmp_path / "missing.mcap")
    assert LogError.user_facing


_WRITER_SCRIPT = r"""
import sys, time, numpy as np
from silbridge.tools.logs.log_synth import synthetic_run, step_slices
from silbridge.shm.records import RECORD_DTYPE
from silbridge.tools.logs.mcap_log import LogWriter
run = synthetic_run(4.0)
w = LogWriter(sys.argv[1], metadata=run.metadata, batch_rows=256)
for k, step in enumerate(step_slices(run)):
    w.write_records(np.concatenate([step[c].view(RECORD_DTYPE) for c in ("/imu", "/gt_att")]))
    w.write("/fc/status", step["/fc/status"])
    if k == 3000:
        print("ready", flush=True)
        time.sleep(60)
"""


def test_killed_writer_leaves_a_readable_log(tmp_path):
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, "-c", _WRITER_SCRIPT, str(path)],
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    log = read_log(path)
    assert log.truncated and log.end is None
    imu = log.channels["/imu"]
    # Every batch finished before the kill is there: at most the staging buffer
    # (4 x 256 records = 512 steps) and one open batch of 256 rows were lost.
    assert 3000 - 512 - 256 <= len(imu) <= 3000
    assert np.all(np.diff(imu["sim_ns"]) == 1_000_000)
    assert log.metadata["config"]["duration_s"] == 4.0
