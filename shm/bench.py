"""Two-process benchmark of the shared-memory ring (`silbridge shm-bench`).

The calling process owns a fresh segment and drives the phases; a child
process (``python -m silbridge.shm.bench --peer NAME``) attaches and plays
the other side. Phases, each `seconds` long:

  py_stream   single-record try_push -> try_pop from Python
  py_batch    numpy batches of 256 (push_batch -> pop_into)
  pingpong    try_push -> wait -> try_pop -> try_push back; round-trip times
  paced_*     1 kHz publishing (sleep, then spin to the deadline); one-way
              latency = consume time - wall_ns stamped at publish. The
              consumer waits by spinning (the ring's own latency), by
              sched_yield, and with the default policy (what a consumer that
              ends up sleeping pays)
  c_stream    the C loops of the extension, batches of 64, verified records
  c_pingpong  the C loops, one record each way

The phases are sequenced through the segment's lockstep words, so the
benchmark also exercises them. Streaming uses overwrite=False rings (the
producer waits for space), so every record must arrive: any loss, reorder
or torn record is reported under `errors`. Figures, never assertions.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

from . import _ring
from .errors import ShmError
from .records import RECORD_DTYPE, Kind, empty
from .segment import Segment, monotonic_ns

# Lockstep words as the benchmark uses them (its own segment, nobody else's).
W_PHASE = 0  # owner: phase number to run
W_DONE = 1   # peer: last phase number finished
W_TOTAL = 2  # owner: records pushed + 1 once a stream phase ends; 1 = stop
BATCH = 256
PACE_HZ = 1000.0
PACE_SPIN_S = 200e-6  # the paced producer sleeps until this long before each deadline
PHASES = ("py_stream", "py_batch", "pingpong", "paced_spin", "paced_yield", "paced_default",
          "c_stream", "c_pingpong")
# How the paced consumer waits: spinning through the whole period, yielding
# through it, or the default policy (spin 20 us, yield to 200 us, then sleep).
PACED_WAIT = {"paced_spin": {"spin_s": 2.0 / PACE_HZ},
              "paced_yield": {"spin_s": 0.0, "yield_s": 2.0 / PACE_HZ},
              "paced_default": {}}
IDLE_S = 10.0  # a side that hears nothing this long gives up (the other died)


class BenchError(ShmError):
    """The benchmark's peer process failed."""


def _percentiles(samples_ns) -> dict:
    a = np.asarray(samples_ns, dtype=np.float64)
    if a.size == 0:
        return {"p50": None, "p99": None, "max": None, "n": 0}
    return {"p50": float(np.percentile(a, 50)), "p99": float(np.percentile(a, 99)),
            "max": float(a.max()), "n": int(a.size)}


# ---------------------------------------------------------------- owner side

def _stream_single(seg: Segment, seconds: float) -> None:
    ring = seg.sensors
    push, free = ring.try_push, ring.free_slots
    rec = empty(Kind.IMU, 1)[0]
    n = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        k = free()  # only push into free slots, so nothing counts as rejected
        for _ in range(min(k, 1024)):
            push(rec)
        n += min(k, 1024)
    seg.set_word(W_TOTAL, n + 1)


def _stream_batch(seg: Segment, seconds: float) -> None:
    ring = seg.sensors
    arr = empty(Kind.IMU, BATCH)
    seq = np.arange(BATCH, dtype=np.uint32)
    n = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for _ in range(64):
            if ring.free_slots() < BATCH:
                continue
            arr["seq"] = seq + np.uint32(n)
            n += ring.push_batch(arr)
    seg.set_word(W_TOTAL, n + 1)


def _pingpong(seg: Segment, seconds: float) -> dict:
    out, back = seg.sensors, seg.actuators
    rec = empty(Kind.IMU, 1)[0]
    rtt = np.empty(int(seconds * 3e6) + 1024, dtype=np.int64)  # beyond any Python rate
    n = 0
    errors = 0
    t_end = monotonic_ns() + int(seconds * 1e9)
    t0 = monotonic_ns()
    while n < rtt.size:
        t = monotonic_ns()
        if t >= t_end:
            break
        out.try_push(rec)
        if not back.wait(IDLE_S):
            errors += 1
            break
        back.try_pop()
        rtt[n] = monotonic_ns() - t
        n += 1
    elapsed = monotonic_ns() - t0
    seg.set_word(W_TOTAL, 1)
    return {"round_trips": n, "elapsed_ns": elapsed, "rtt": rtt[:n], "errors": errors}


def _paced(seg: Segment, seconds: float) -> int:
    ring = seg.sensors
    rec = empty(Kind.IMU, 1)[0]
    period_ns = int(1e9 / PACE_HZ)
    spin_ns = int(PACE_SPIN_S * 1e9)
    n = 0
    t_next = monotonic_ns() + period_ns
    t_end = t_next + int(seconds * 1e9)
    while t_next < t_end:
        ahead = t_next - monotonic_ns() - spin_ns
        if ahead > 0:
            time.sleep(ahead / 1e9)
        while monotonic_ns() < t_next:
            pass
        ring.try_push(rec)  # stamps wall_ns at publish
        n += 1
        t_next += period_ns
    seg.set_word(W_TOTAL, n + 1)
    return n


# ----------------------------------------------------------------- peer side

def _peer_stream_single(seg: Segment) -> dict:
    ring = seg.sensors
    pop = ring.try_pop
    got = 0
    t_first = t_last = 0
    idle_since = time.monotonic()
    while True:
        if pop() is not None:
            if got == 0:
                t_first = monotonic_ns()
            got += 1
            continue
        total = seg.word(W_TOTAL)
        if total and got >= total - 1:
            t_last = monotonic_ns()
            break
        if ring.wait(0.05):
            idle_since = time.monotonic()
        elif time.monotonic() - idle_since > IDLE_S:
            break
    total = seg.word(W_TOTAL) - 1
    return {"records": got, "elapsed_ns": t_last - t_first, "errors": int(got != total)}


def _peer_stream_batch(seg: Segment) -> dict:
    ring = seg.sensors
    out = np.empty(BATCH * 4, dtype=RECORD_DTYPE)
    seq = out["seq"]
    got = 0
    errors = 0
    expect = 0
    t_first = t_last = 0
    idle_since = time.monotonic()
    while True:
        k = ring.pop_into(out)
        if k:
            if got == 0:
                t_first = monotonic_ns()
            # O(1) check per batch: the batch starts where the last ended and is contiguous.
            first, last = int(seq[0]), int(seq[k - 1])
            if first != expect or (last - first) & 0xFFFFFFFF != k - 1:
                errors += 1
            expect = (last + 1) & 0xFFFFFFFF
            got += k
            continue
        total = seg.word(W_TOTAL)
        if total and got >= total - 1:
            t_last = monotonic_ns()
            break
        if ring.wait(0.05):
            idle_since = time.monotonic()
        elif time.monotonic() - idle_since > IDLE_S:
            break
    total = seg.word(W_TOTAL) - 1
    return {"records": got, "elapsed_ns": t_last - t_first, "errors": errors + int(got != total)}


def _peer_echo(seg: Segment) -> dict:
    inbox, outbox = seg.sensors, seg.actuators
    n = 0
    while True:
        if inbox.wait(0.05):
            outbox.try_push(inbox.try_pop())
            n += 1
        elif seg.word(W_TOTAL):
            break
    return {"echoed": n}


def _peer_paced(seg: Segment, wait_kw: dict) -> dict:
    ring = seg.sensors
    lat = []
    while True:
        if ring.wait(0.05, **wait_kw):
            rec = ring.try_pop()
            lat.append(monotonic_ns() - int(rec["wall_ns"]))
            continue
        total = seg.word(W_TOTAL)
        if total and len(lat) >= total - 1:
            break
    return {"one_way": _percentiles(lat), "received": len(lat)}


def _peer_c_stream(seg: Segment) -> dict:
    return _ring.c_stream_bench(seg.sensors, 0.0, 64, IDLE_S)


def _peer_c_pingpong(seg: Segment) -> dict:
    res = _ring.c_pingpong_bench(seg.sensors, seg.actuators, 0.0, IDLE_S)
    res.pop("rtt_ns")  # the echoing side takes no samples
    return res


PEER_PHASES = {
    "py_stream": _peer_stream_single,
    "py_batch": _peer_stream_batch,
    "pingpong": _peer_echo,
    **{p: (lambda seg, kw=kw: _peer_paced(seg, kw)) for p, kw in PACED_WAIT.items()},
    "c_stream": _peer_c_stream,
    "c_pingpong": _peer_c_pingpong,
}


def run_peer(name: str) -> int:
    """The child process: attach, then play each phase the owner starts."""
    seg = Segment.attach(name, timeout_s=IDLE_S)
    results = {}
    for phase_no, phase in enumerate(PHASES, start=1):
        if not seg.wait_word(W_PHASE, phase_no, IDLE_S):
            results["error"] = f"owner never started phase {phase}"
            break
        results[phase] = PEER_PHASES[phase](seg)
        seg.set_word(W_DONE, phase_no)
    print(json.dumps(results), flush=True)
    seg.close()
    return 0


# ------------------------------------------------------------------ driver

def run(seconds: float = 1.0, name: str | None = None) -> dict:
    """Run every phase for `seconds` each; returns the figures as a dict."""
    name = name or f"shm-bench-{os.getpid()}"
    res: dict = {"seconds_per_phase": seconds}
    with Segment.create(name, sensor_slots=1 << 14, actuator_slots=1 << 10,
                        overwrite=False) as seg:
        peer = subprocess.Popen([sys.executable, "-m", "silbridge.shm.bench", "--peer", name],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            owner = _drive(seg, seconds)
            out, err = peer.communicate(timeout=IDLE_S + 5 * seconds + 30)
        finally:
            if peer.poll() is None:
                peer.kill()
                peer.wait()
        if peer.returncode != 0 or not out.strip():
            raise BenchError(f"the benchmark's peer process failed (exit {peer.returncode}): "
                             f"{err.strip()[-400:]}")
        stats = {"sensors": seg.sensors.stats(), "actuators": seg.actuators.stats()}
    peer_res = json.loads(out.strip().splitlines()[-1])
    return _summarise(res, owner, peer_res, stats)


def _owner_c_stream(seg: Segment, seconds: float) -> dict:
    return _ring.c_stream_bench(seg.sensors, seconds, 64, IDLE_S)


def _owner_c_pingpong(seg: Segment, seconds: float) -> dict:
    return _ring.c_pingpong_bench(seg.actuators, seg.sensors, seconds, IDLE_S)


OWNER_PHASES = {
    "py_stream": _stream_single,
    "py_batch": _stream_batch,
    "pingpong": _pingpong,
    **{p: _paced for p in PACED_WAIT},
    "c_stream": _owner_c_stream,
    "c_pingpong": _owner_c_pingpong,
}


def _drive(seg: Segment, seconds: float) -> dict:
    if not _wait_peer(seg):
        raise BenchError("the benchmark's peer process never attached")
    owner: dict = {}
    for phase_no, phase in enumerate(PHASES, start=1):
        seg.set_word(W_TOTAL, 0)
        seg.set_word(W_PHASE, phase_no)
        owner[phase] = OWNER_PHASES[phase](seg, seconds)
        if not seg.wait_word(W_DONE, phase_no, IDLE_S + seconds):
            raise BenchError(f"the benchmark's peer process stalled in phase {phase}")
    return owner


def _wait_peer(seg: Segment) -> bool:
    deadline = time.monotonic() + IDLE_S
    while time.monotonic() < deadline:
        if seg.peer_pid:
            return True
        time.sleep(0.005)
    return False


def _rate(r: dict, key: str = "records") -> float:
    return r[key] * 1e9 / r["elapsed_ns"] if r.get("elapsed_ns") else 0.0


def _p3(paced: dict) -> dict:
    return {k: paced["one_way"][k] for k in ("p50", "p99", "max")}


def _summarise(res: dict, owner: dict, peer: dict, stats: dict) -> dict:
    pp = owner["pingpong"]
    cpp = owner["c_pingpong"]
    c_rtt = np.frombuffer(cpp.pop("rtt_ns"), dtype=np.int64)
    cs = peer["c_stream"]
    rtt = _percentiles(pp["rtt"])
    c_rtt_p = _percentiles(c_rtt)
    errors = (peer["py_stream"]["errors"] + peer["py_batch"]["errors"] + pp["errors"]
              + cs["torn"] + cs["reordered"] + int(cs["lost_by_seq"] != cs["overwritten"])
              + int(cs["timed_out"]) + cpp["errors"] + int(cpp["timed_out"])
              + peer["c_pingpong"]["errors"]
              + sum(int(peer[p]["received"] != owner[p]) for p in PACED_WAIT))
    res.update({
        "stream_records_per_s": _rate(peer["py_stream"]),
        "batch_records_per_s": _rate(peer["py_batch"]),
        "pingpong_round_trips_per_s": _rate(pp, "round_trips"),
        "rtt_ns": {"p50": rtt["p50"], "p99": rtt["p99"]},
        "one_way_ns": _p3(peer["paced_spin"]),
        "one_way_yield_wait_ns": _p3(peer["paced_yield"]),
        "one_way_default_wait_ns": _p3(peer["paced_default"]),
        "c_stream_records_per_s": cs["records_per_s"],
        "c_pingpong_round_trips_per_s": cpp["round_trips_per_s"],
        "c_rtt_ns": {"p50": c_rtt_p["p50"], "p99": c_rtt_p["p99"]},
        "overwritten": sum(s["overwritten"] for s in stats.values()),
        "rejected": sum(s["rejected"] for s in stats.values()),
        "errors": int(errors),
        "records_checked": {"py_stream": peer["py_stream"]["records"],
                            "py_batch": peer["py_batch"]["records"],
                            "c_stream": cs["records"]},
    })
    return res


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m silbridge.shm.bench")
    p.add_argument("--peer", metavar="NAME", help="run as the attaching peer of segment NAME")
    p.add_argument("--seconds", type=float, default=1.0)
    args = p.parse_args(argv)
    if args.peer:
        return run_peer(args.peer)
    print(json.dumps(run(args.seconds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
