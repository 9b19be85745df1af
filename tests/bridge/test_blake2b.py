"""The trace hash's BLAKE2b in C (bridge/src/blake2b.c, the _step.Blake2b object a batch
feeds from C while the FC computes its answer) gives hashlib's digest: a run's trace hash
is the same string it was when Python hashed the records with hashlib."""

import hashlib

import numpy as np
import pytest

from silbridge.bridge import _step
from silbridge.shm.records import RECORD_DTYPE


@pytest.mark.parametrize("digest_size", [1, 16, 32, 64])
def test_digest_is_hashlibs(digest_size):
    """Messages around the 128-byte block edges (the last block is compressed with the
    final flag, so a message of exactly k blocks is the edge case), fed in odd pieces."""
    rng = np.random.default_rng(digest_size)
    for n in (0, 1, 127, 128, 129, 255, 256, 257, 4095, 4096, 4097, 70_000):
        msg = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        ours = _step.Blake2b(digest_size=digest_size)
        at = 0
        while at < n:
            k = int(rng.integers(0, 300))
            ours.update(msg[at:at + k])
            at += k
        ref = hashlib.blake2b(msg, digest_size=digest_size)
        assert ours.digest() == ref.digest(), n
        assert ours.hexdigest() == ref.hexdigest(), n


def test_digest_mid_stream_then_more():
    """digest() leaves the state as it was: the run's hash can be read, then fed on."""
    ours, ref = _step.Blake2b(digest_size=16), hashlib.blake2b(digest_size=16)
    for chunk in (b"a" * 200, b"b" * 56, b"c" * 300):
        ours.update(chunk)
        ref.update(chunk)
        assert ours.hexdigest() == ref.hexdigest()


def test_records_hash_as_their_bytes():
    """The per-step path feeds structured record arrays and byte views, as it fed hashlib."""
    recs = np.zeros(50, dtype=RECORD_DTYPE)
    recs.view(np.uint8)[:] = np.arange(recs.nbytes) % 251
    raw = memoryview(recs.view(np.uint8))
    ours = _step.Blake2b(digest_size=16)
    ours.update(recs[3:40])
    ours.update(raw[:100])
    ref = hashlib.blake2b(recs[3:40].tobytes() + bytes(raw[:100]), digest_size=16)
    assert ours.hexdigest() == ref.hexdigest()


def test_bad_digest_size_and_input_are_refused():
    with pytest.raises(ValueError, match="digest_size"):
        _step.Blake2b(digest_size=65)
    with pytest.raises(TypeError):
        _step.Blake2b().update("text is not bytes")


def test_a_hash_fed_on_its_thread_is_hashlibs():
    """update_later on the thread, interleaved with update and digests (each waits for the
    job before), two buffers in turn as the one-process loop uses them: hashlib's digest."""
    rng = np.random.default_rng(7)
    ours, ref = _step.Blake2b(digest_size=16), hashlib.blake2b(digest_size=16)
    assert ours.start_thread() is True
    assert ours.start_thread() is True          # a second start keeps the one thread
    bufs = [np.zeros(300_000, dtype=np.uint8) for _ in range(2)]
    for i in range(60):
        buf = bufs[i % 2]
        n = int(rng.integers(0, len(buf)))
        buf[:n] = rng.integers(0, 256, n, dtype=np.uint8)
        ours.update_later(memoryview(buf)[:n])
        ref.update(buf[:n].tobytes())
        if i % 7 == 3:
            small = rng.integers(0, 256, 77, dtype=np.uint8).tobytes()
            ours.update(small)
            ref.update(small)
        if i % 11 == 5:
            assert ours.hexdigest() == ref.hexdigest(), i
    assert ours.digest() == ref.digest()


def test_update_later_without_a_thread_hashes_at_once():
    ours, ref = _step.Blake2b(digest_size=16), hashlib.blake2b(digest_size=16)
    buf = bytearray(b"x" * 1000)
    ours.update_later(buf)
    buf[:] = b"y" * 1000           # no thread: the bytes were taken already
    ref.update(b"x" * 1000)
    assert ours.hexdigest() == ref.hexdigest()


def _os_threads() -> int:
    with open("/proc/self/status") as f:
        return int(next(line for line in f if line.startswith("Threads:")).split()[1])


def test_a_threaded_hash_let_go_mid_job_stops_cleanly():
    """Dropped with a job pending (a run stopped between batches): the job finishes, the
    thread is joined, none is left behind."""
    before = _os_threads()
    for _ in range(20):
        h = _step.Blake2b(digest_size=16)
        assert h.start_thread()
        h.update_later(np.ones(2_000_000, dtype=np.uint8))
        assert _os_threads() == before + 1
        del h
    assert _os_threads() == before
