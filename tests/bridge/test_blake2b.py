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
