"""The other process of the two-process shm tests (not a test module).

    python peer_proc.py MODE NAME [options]

Modes (each prints JSON lines on stdout; the last one is its result):
  c-consume NAME BATCH           attach, run the C stream consumer (pops of BATCH)
  py-produce NAME N SEED         attach as peer, push N fuzz records on the
                                 actuator ring in random-size numpy batches
  owner-stream NAME RATE_HZ      create the segment, stream fuzz records on the
                                 sensor ring at about RATE_HZ until killed
  consume NAME N                 attach, pop N sensor records, print their
                                 indices, then wait (to be killed or closed)
Fuzz record i: sim_ns = i, seq = i mod 2^32, payload = five uint64 words
i * GOLDEN + k, the same pattern as the C loops (shm/src/bench.c).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from silbridge.shm import Segment, _ring
from silbridge.shm.records import RECORD_DTYPE, Kind

GOLDEN = np.uint64(0x9E3779B97F4A7C15)


def fuzz_records(start: int, n: int) -> np.ndarray:
    """n fuzz records with indices start .. start + n - 1."""
    idx = np.arange(start, start + n, dtype=np.uint64)
    arr = np.zeros(n, dtype=RECORD_DTYPE)
    arr["kind"] = int(Kind.IMU)
    arr["seq"] = (idx & np.uint64(0xFFFFFFFF)).astype(np.uint32)
    arr["sim_ns"] = idx.astype(np.int64)
    words = arr.view(np.uint64).reshape(n, 8)[:, 3:]
    with np.errstate(over="ignore"):
        words[:] = idx[:, None] * GOLDEN + np.arange(5, dtype=np.uint64)[None, :]
    return arr


def intact(arr: np.ndarray) -> np.ndarray:
    """Per record: True when every field agrees with its index (not torn)."""
    idx = arr["sim_ns"].astype(np.uint64)
    words = np.ascontiguousarray(arr).view(np.uint64).reshape(len(arr), 8)[:, 3:]
    with np.errstate(over="ignore"):
        want = idx[:, None] * GOLDEN + np.arange(5, dtype=np.uint64)[None, :]
    return ((words == want).all(axis=1) & (arr["kind"] == int(Kind.IMU))
            & (arr["seq"] == (idx & np.uint64(0xFFFFFFFF)).astype(np.uint32)))


def say(**kw) -> None:
    print(json.dumps(kw), flush=True)


def c_consume(name: str, batch: int) -> None:
    seg = Segment.attach(name, timeout_s=10.0)
    say(attached=True)
    say(**_ring.c_stream_bench(seg.sensors, 0.0, batch, 20.0))
    seg.close()


def py_produce(name: str, n: int, seed: int) -> None:
    seg = Segment.attach(name, timeout_s=10.0)
    ring = seg.actuators
    rng = np.random.default_rng(seed)
    i = 0
    deadline = time.monotonic() + 60.0
    while i < n and time.monotonic() < deadline:
        k = min(int(rng.integers(1, 300)), n - i)
        space = ring.free_slots()
        if space == 0:
            time.sleep(0)  # the consumer is behind: let it run
            continue
        k = min(k, space)
        assert ring.push_batch(fuzz_records(i, k), stamp=bool(i & 1)) == k
        i += k
    say(pushed=i)
    seg.close()


def owner_stream(name: str, rate_hz: float) -> None:
    seg = Segment.create(name, sensor_slots=1 << 12, actuator_slots=1 << 6)
    say(created=True)
    ring = seg.sensors
    period = 1.0 / rate_hz
    i = 0
    t_next = time.monotonic()
    while True:  # until killed
        ring.push_batch(fuzz_records(i, 10))
        i += 10
        seg.beat()
        t_next += 10 * period
        delay = t_next - time.monotonic()
        if delay > 0:
            time.sleep(delay)


def consume(name: str, n: int) -> None:
    seg = Segment.attach(name, timeout_s=10.0)
    ring = seg.sensors
    got = []
    deadline = time.monotonic() + 30.0
    while len(got) < n and time.monotonic() < deadline:
        if ring.wait(0.1):
            rec = ring.try_pop()
            got.append(int(rec["sim_ns"]))
    say(indices=got)
    time.sleep(60.0)  # hold the attachment until the test kills us


def main(argv: list[str]) -> int:
    mode, name = argv[0], argv[1]
    if mode == "c-consume":
        c_consume(name, int(argv[2]))
    elif mode == "py-produce":
        py_produce(name, int(argv[2]), int(argv[3]))
    elif mode == "owner-stream":
        owner_stream(name, float(argv[2]))
    elif mode == "consume":
        consume(name, int(argv[2]))
    else:
        raise SystemExit(f"unknown mode {mode}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
