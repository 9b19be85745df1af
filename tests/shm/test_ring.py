"""Ring behaviour through two mappings in one process: push/pop, batches,
stamping, overwrite accounting when the consumer stalls, refusal when the
ring does not overwrite, roles, waits, words and heartbeats."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from silbridge.shm import RecordKindError, RingRoleError, Segment, SegmentClosedError
from silbridge.shm.records import IMU_DTYPE, PWM_DTYPE, RECORD_DTYPE, Kind, empty


def imu(n: int, start: int = 0) -> np.ndarray:
    arr = empty(Kind.IMU, n)
    arr["seq"] = np.arange(start, start + n)
    arr["sim_ns"] = np.arange(start, start + n) * 1000
    arr["accel_frd_m_s2"][:, 2] = -9.81
    return arr


@pytest.fixture
def pair(name):
    """(owner, peer) mappings of one segment with small rings."""
    owner = Segment.create(name, sensor_slots=64, actuator_slots=16)
    peer = Segment.attach(name)
    yield owner, peer
    peer.close()
    owner.unlink()
    owner.close()


def test_single_record_round_trip_keeps_every_field(pair):
    owner, peer = pair
    rec = imu(1, start=7)[0]
    assert owner.sensors.try_push(rec)
    got = peer.sensors.try_pop()
    assert isinstance(got, np.void) and got.dtype == RECORD_DTYPE
    view = np.frombuffer(got.tobytes(), dtype=IMU_DTYPE)[0]
    assert view["seq"] == 7 and view["sim_ns"] == 7000
    assert view["accel_frd_m_s2"][2] == np.float32(-9.81)
    assert peer.sensors.try_pop() is None


def test_push_stamps_wall_ns_unless_told_not_to(pair):
    owner, peer = pair
    rec = imu(1)[0]
    rec["wall_ns"] = 123
    before = time.monotonic_ns()
    owner.sensors.try_push(rec)
    owner.sensors.try_push(rec, stamp=False)
    stamped, kept = peer.sensors.try_pop(), peer.sensors.try_pop()
    assert before <= stamped["wall_ns"] <= time.monotonic_ns()
    assert kept["wall_ns"] == 123
    assert rec["wall_ns"] == 123  # the caller's record is never modified


def test_bytes_and_any_record_dtype_are_accepted(pair):
    owner, peer = pair
    pwm = empty(Kind.PWM, 1)
    pwm["pwm_us"][0, :4] = [1100, 1200, 1300, 1400]
    assert peer.actuators.try_push(pwm[0].tobytes())
    assert peer.actuators.push_batch(pwm) == 1
    out = owner.actuators.pop_batch(10).view(PWM_DTYPE)
    assert len(out) == 2 and (out["pwm_us"][:, :4] == [1100, 1200, 1300, 1400]).all()


def test_batches_preserve_order_across_wrap_around(pair):
    owner, peer = pair
    expect = 0
    out = np.empty(40, dtype=RECORD_DTYPE)
    for round_no in range(20):  # 20 x 37 records through 64 slots: wraps many times
        assert owner.sensors.push_batch(imu(37, start=round_no * 37)) == 37
        got = peer.sensors.pop_into(out)
        assert got == 37
        assert (out["seq"][:got] == np.arange(expect, expect + got)).all()
        expect += got
    st = owner.sensors.stats()
    assert st["written"] == st["read"] == 740 and st["overwritten"] == 0


def test_pop_batch_returns_at_most_max_n(pair):
    owner, peer = pair
    owner.sensors.push_batch(imu(10))
    assert len(peer.sensors.pop_batch(0)) == 0
    assert list(peer.sensors.pop_batch(4)["seq"]) == [0, 1, 2, 3]
    assert list(peer.sensors.pop_batch(100)["seq"]) == [4, 5, 6, 7, 8, 9]
    assert peer.sensors.pop_batch(100).shape == (0,)


def test_stalled_consumer_loses_oldest_and_everything_is_counted(pair):
    owner, peer = pair
    ring_p, ring_c = owner.sensors, peer.sensors
    ring_p.push_batch(imu(10))
    assert len(ring_c.pop_batch(10)) == 10
    # The consumer stalls while 1000 records go through a 64-slot ring.
    for start in range(10, 1010, 50):
        ring_p.push_batch(imu(50, start=start))
    st = ring_p.stats()
    assert st["written"] == 1010
    assert st["written"] == st["read"] + st["overwritten"] + st["available"]
    got = ring_c.pop_batch(1000)
    seq = got["seq"].astype(np.int64)
    # What survives is the newest records, contiguous and in order, ending at the last.
    assert seq[-1] == 1009 and (np.diff(seq) == 1).all()
    assert 0 < len(got) < 64
    st = ring_c.stats()
    assert st["read"] == 10 + len(got)
    assert st["overwritten"] == 1010 - st["read"]
    assert st["available"] == 0
    # After resynchronising it continues normally.
    ring_p.try_push(imu(1, start=1010)[0])
    assert ring_c.try_pop()["seq"] == 1010


def test_single_pops_after_a_lap_resynchronise(pair):
    owner, peer = pair
    owner.sensors.push_batch(imu(200))
    first = peer.sensors.try_pop()["seq"]
    assert first > 200 - 64
    rest = [peer.sensors.try_pop()["seq"] for _ in range(199 - first)]
    assert rest == list(range(first + 1, 200))
    assert peer.sensors.stats()["overwritten"] == first


def test_ring_without_overwrite_refuses_and_counts_rejected(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16, overwrite=False) as owner:
        peer = Segment.attach(name)
        assert owner.sensors.push_batch(imu(20)) == 16
        assert owner.sensors.free_slots() == 0
        assert not owner.sensors.try_push(imu(1, start=20)[0])
        assert owner.sensors.stats()["rejected"] == 5
        assert list(peer.sensors.pop_batch(100)["seq"]) == list(range(16))
        assert owner.sensors.free_slots() == 16
        assert owner.sensors.try_push(imu(1, start=16)[0])
        assert peer.sensors.stats() == {"written": 17, "read": 16, "overwritten": 0,
                                        "rejected": 5, "available": 1}
        peer.close()


def test_each_side_may_only_do_its_own_verb(pair):
    owner, peer = pair
    with pytest.raises(RingRoleError, match="bridge"):
        peer.sensors.try_push(imu(1)[0])
    with pytest.raises(RingRoleError):
        owner.sensors.try_pop()
    with pytest.raises(RingRoleError):
        owner.actuators.push_batch(imu(1))
    with pytest.raises(RingRoleError):
        peer.actuators.pop_batch(1)


def test_unknown_kind_is_refused_before_anything_is_written(pair):
    owner, peer = pair
    bad = imu(5)
    bad["kind"][3] = 99
    with pytest.raises(RecordKindError, match="unknown kind 99"):
        owner.sensors.push_batch(bad)
    with pytest.raises(RecordKindError):
        owner.sensors.try_push(np.zeros(1, RECORD_DTYPE)[0])  # kind 0 = NONE
    assert owner.sensors.stats()["written"] == 0
    assert RecordKindError.user_facing


def test_wrong_record_size_is_refused(pair):
    owner, _ = pair
    with pytest.raises(ValueError, match="64 bytes"):
        owner.sensors.try_push(b"\x01" * 63)
    with pytest.raises(ValueError, match="itemsize"):
        owner.sensors.push_batch(np.zeros(3, dtype=np.float64))
    with pytest.raises(ValueError, match="whole number"):
        owner.sensors.push_batch(b"\x01\x00" * 40)


def test_wait_returns_false_after_timeout_and_true_when_data_arrives(pair):
    owner, peer = pair
    t0 = time.monotonic()
    assert not peer.sensors.wait(0.02)
    assert time.monotonic() - t0 >= 0.019
    assert not peer.sensors.poll()

    def later():
        time.sleep(0.03)
        owner.sensors.try_push(imu(1)[0])

    t = threading.Thread(target=later)
    t.start()  # the wait releases the GIL while it yields/sleeps, so this thread runs
    assert peer.sensors.wait(5.0)
    t.join()
    assert peer.sensors.poll() and peer.sensors.available() == 1


def test_words_wait_and_heartbeats(pair):
    owner, peer = pair
    owner.set_word(3, 2**64 - 1)
    assert peer.word(3) == 2**64 - 1
    assert not peer.wait_word(0, 5, 0.01)
    with pytest.raises(IndexError):
        owner.word(9)

    def later():
        time.sleep(0.02)
        peer.set_word(1, 10)

    t = threading.Thread(target=later)
    t.start()
    assert owner.wait_word(1, 10, 5.0)
    t.join()
    assert owner.beat() == 1 and owner.beat() == 2
    assert peer.peer_heartbeat() == 2 and owner.peer_heartbeat() == 0
    peer.beat()
    assert owner.peer_heartbeat() == 1


def test_peer_identity_and_liveness(pair):
    owner, peer = pair
    import os
    assert owner.peer_pid == os.getpid() and peer.peer_pid == os.getpid()
    assert owner.peer_alive() and peer.peer_alive()
    peer.close()
    assert not owner.peer_alive()
    with pytest.raises(SegmentClosedError):
        peer.sensors
    assert owner.info["peer_attaches"] == 1


def test_restarted_consumer_continues_from_the_tail(name):
    with Segment.create(name, sensor_slots=64, actuator_slots=16) as owner:
        first = Segment.attach(name)
        owner.sensors.push_batch(imu(30))
        assert len(first.sensors.pop_batch(12)) == 12
        first.close()
        again = Segment.attach(name)
        assert list(again.sensors.pop_batch(100)["seq"]) == list(range(12, 30))
        assert owner.info["peer_attaches"] == 2
        again.close()


def test_owner_sees_no_peer_before_attach(name):
    with Segment.create(name, sensor_slots=16, actuator_slots=16) as owner:
        assert owner.peer_pid == 0 and not owner.peer_alive()
        assert owner.sensors.capacity == 16 and owner.sensors.overwrite
        assert owner.sensors.produces and not owner.actuators.produces


def test_forked_child_dropping_an_inherited_segment_leaves_it_open(name):
    import os
    with Segment.create(name, sensor_slots=16, actuator_slots=16) as owner:
        pid = os.fork()
        if pid == 0:  # child: close the inherited handles the way a GC would
            owner.close()
            os._exit(0)
        os.waitpid(pid, 0)
        peer = Segment.attach(name)  # the owner is neither closed nor unlocked
        assert peer.peer_alive() and peer.peer_pid == os.getpid()
        peer.close()
