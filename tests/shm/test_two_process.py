"""Two real processes on one segment: fuzzing with millions of records
(sequence and checksum verified: nothing torn, lost unaccounted or
reordered), the owner killed mid-stream, and a consumer restarted."""

from __future__ import annotations

import importlib.util
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from silbridge.shm import OwnerDeadError, PeerBusyError, Segment, _ring
from silbridge.shm.records import RECORD_DTYPE

_spec = importlib.util.spec_from_file_location("shm_peer_proc",
                                               Path(__file__).with_name("peer_proc.py"))
peer_proc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(peer_proc)


def _wait_attached(seg: Segment, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not seg.peer_pid:
        assert time.monotonic() < deadline, "the helper never attached"
        time.sleep(0.002)


def test_c_fuzz_without_overwrite_delivers_every_record_intact(name, helpers):
    with Segment.create(name, sensor_slots=1 << 10, actuator_slots=16,
                        overwrite=False) as seg:
        proc = helpers.spawn("c-consume", name, "64")
        _wait_attached(seg)
        # 3 M records; the 20 s cap only guards against a hang.
        prod = _ring.c_stream_bench(seg.sensors, 20.0, 37, 20.0, max_records=3_000_000)
        cons = helpers.finish(proc)
    assert not prod["timed_out"] and not cons["timed_out"]
    assert prod["records"] == cons["records"] == 3_000_000
    assert cons["torn"] == cons["reordered"] == cons["lost_by_seq"] == 0
    assert cons["overwritten"] == 0


@pytest.mark.parametrize("slots, pop_batch, push_batch", [(4, 4, 1), (8, 8, 4), (64, 64, 1)])
def test_c_fuzz_with_overwrite_accounts_for_every_lost_record(name, helpers, slots, pop_batch,
                                                               push_batch):
    # Small rings and a fast producer: the consumer is lapped over and over,
    # also in the middle of its copies, which only the post-copy head check
    # catches (without it these cases show reordered records and losses
    # the ring did not count).
    with Segment.create(name, sensor_slots=slots, actuator_slots=16, overwrite=True) as seg:
        proc = helpers.spawn("c-consume", name, str(pop_batch))
        _wait_attached(seg)
        prod = _ring.c_stream_bench(seg.sensors, 0.7, push_batch, 20.0)
        cons = helpers.finish(proc)
        stats = seg.sensors.stats()
    assert cons["torn"] == 0 and cons["reordered"] == 0
    assert cons["lost_by_seq"] == cons["overwritten"]
    assert cons["records"] + cons["lost_by_seq"] == prod["records"]
    assert stats["written"] == stats["read"] + stats["overwritten"] + stats["available"]
    assert cons["records"] > 0


@pytest.mark.parametrize("overwrite", [False, True])
def test_python_batch_fuzz(name, helpers, overwrite):
    n = 1_500_000 if not overwrite else 600_000
    rng = np.random.default_rng(7)
    out = np.empty(512, dtype=RECORD_DTYPE)
    with Segment.create(name, sensor_slots=16, actuator_slots=256,
                        overwrite=overwrite) as seg:
        proc = helpers.spawn("py-produce", name, str(n), "11")
        _wait_attached(seg)
        ring = seg.actuators
        expect, received, lost, bad = 0, 0, 0, 0
        deadline = time.monotonic() + 60
        while expect < n and time.monotonic() < deadline:
            view = out[: int(rng.integers(1, 513))]
            if int(rng.integers(0, 8)) == 0:
                got = view[: ring.pop_into(view)]
            else:
                got = ring.pop_batch(len(view))
            if len(got) == 0:
                if proc.poll() is not None and not ring.poll():
                    break
                ring.wait(0.01)
                continue
            bad += int((~peer_proc.intact(got)).sum())
            idx = got["sim_ns"].astype(np.int64)
            assert idx[0] >= expect and (np.diff(idx) == 1).all(), "reordered or inner gap"
            lost += int(idx[0] - expect)
            expect = int(idx[-1]) + 1
            received += len(got)
        result = helpers.finish(proc)
        stats = ring.stats()
    assert bad == 0
    assert result["pushed"] == n and expect == n
    assert received + lost == n
    assert stats["overwritten"] == lost and stats["read"] == received
    if not overwrite:
        assert lost == 0


def test_owner_killed_mid_stream(name, helpers):
    proc = helpers.spawn("owner-stream", name, "5000")  # 4096 slots hold 0.8 s of it
    assert helpers.read_line(proc)["created"]
    seg = Segment.attach(name, timeout_s=20.0)
    ring = seg.sensors
    expect = None
    t_end = time.monotonic() + 0.3
    while time.monotonic() < t_end:
        got = ring.pop_batch(256)
        if len(got):
            assert peer_proc.intact(got).all()
            if expect is not None:
                assert got["sim_ns"][0] == expect
            expect = int(got["sim_ns"][-1]) + 1
        else:
            ring.wait(0.01)
    assert expect and expect > 100
    assert seg.peer_alive() and seg.peer_heartbeat() > 0
    proc.send_signal(signal.SIGKILL)
    os.waitid(os.P_PID, proc.pid, os.WEXITED | os.WNOWAIT)  # exited, not yet reaped
    assert not seg.peer_alive()
    proc.wait(10)
    beats = seg.peer_heartbeat()
    # What was published before the kill is still readable, intact and in order.
    rest = ring.pop_batch(1 << 12)
    if len(rest):
        assert peer_proc.intact(rest).all() and rest["sim_ns"][0] == expect
        assert (np.diff(rest["sim_ns"]) == 1).all()
    assert not ring.wait(0.05) and seg.peer_heartbeat() == beats
    seg.close()
    with pytest.raises(OwnerDeadError, match="Restart the bridge"):
        Segment.attach(name)
    with Segment.create(name, sensor_slots=16, actuator_slots=16) as fresh:  # stale replaced
        assert fresh.sensors.stats()["written"] == 0


def test_restarted_consumer_process_continues_where_the_killed_one_stopped(name, helpers):
    n = 1000
    with Segment.create(name, sensor_slots=1 << 11, actuator_slots=16,
                        overwrite=False) as seg:
        seg.sensors.push_batch(peer_proc.fuzz_records(0, n))
        first = helpers.spawn("consume", name, "300")
        assert helpers.read_line(first)["indices"] == list(range(300))
        with pytest.raises(PeerBusyError):
            Segment.attach(name)  # the first consumer still lives
        first.send_signal(signal.SIGKILL)
        # Wait for it to exit but leave it unreaped: a zombie still "exists" for
        # kill(pid, 0), yet its peer lock is gone, so it must not count as alive.
        os.waitid(os.P_PID, first.pid, os.WEXITED | os.WNOWAIT)
        assert not seg.peer_alive()
        first.wait(10)
        second = helpers.spawn("consume", name, str(n - 300))
        assert helpers.read_line(second)["indices"] == list(range(300, n))
        assert seg.peer_pid == second.pid and seg.info["peer_attaches"] == 2
        stats = seg.sensors.stats()
        assert stats["read"] == n and stats["overwritten"] == 0
