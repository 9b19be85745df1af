"""Benchmark of run logging: its cost per physics step, and read-back time.

Two measurements, because a writer's cost depends on where it runs:

1. Synthetic replay: a synthetic run (tools/logs/log_synth.py) at IMU 1 kHz is
   replayed the way a Python loop logs (the MAVLink HIL links' FC loop): per
   physics step the sensor and ground-truth records the FC consumed, its status
   rows, the timing row and the PWM records, either as four calls
   (`write_records`, `write`, `pack`, `write_records`) or as one `write_cycle`
   (tools/loop/run_log.py), and `write_cycle` with the viewable /viz channels on
   (tools/logs/viz_log.py, at 1 kHz). Hot caches, so this is the writer's floor.
   Also bulk writes (ns per row), file size and the time `read_log` takes to
   read every channel back, with and without the viewable channels.
2. Real loop A/B/C: `silbridge fly --processes 1` itself, in turn without a
   log, with --log --viz-hz 0 (the analysis channels only: the FC's C core
   appends records to the log's queues, Core.bind_log) and with --log (the
   viewable channels too); the loop thread's CPU time per physics step of
   each logged flight against the unlogged flight just before it is what
   logging adds, caches and all.

Both measurements interleave their variants, so that machine noise (other
processes on the 2 cores) hits all alike, and report medians and bests.
Nothing is asserted.

    python -m silbridge.tools.logs.log_bench [--duration 120] [--pairs 6] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np

from silbridge.shm.records import RECORD_DTYPE
from silbridge.tools.logs.log_synth import step_slices, synthetic_run, write_run
from silbridge.tools.logs.mcap_log import TIMING_DTYPE, LogWriter, read_log

RECORD_CHANNELS = ("/imu", "/baro", "/mag", "/gnss", "/gt_att", "/gt_nav")


def _per_step_inputs(run):
    """Per step: (mixed sensor records, pwm records, status rows, timing row values)."""
    steps = []
    for s in step_slices(run):
        recs = np.concatenate([s[c].view(RECORD_DTYPE) for c in RECORD_CHANNELS if len(s[c])])
        timing = tuple(int(v) for v in s["/timing"][0])
        steps.append((recs, s["/pwm"], s["/fc/status"], timing))
    return steps


def _log_separately(w, recs, pwm, st, timing) -> None:
    w.write_records(recs)
    if len(st):
        w.write("/fc/status", st)
    w.pack("/timing", *timing)
    w.write_records(pwm)


def _log_cycle(w, recs, pwm, st, timing) -> None:
    w.write_cycle(recs, st, timing, pwm)


STYLES = {"separate": _log_separately, "cycle": _log_cycle, "cycle_viz": _log_cycle}
VIZ_HZ = {"separate": 0, "cycle": 0, "cycle_viz": 1000.0}   # viewable channels per style


def bench_replay(run, tmpdir: str, block: int = 500, **writer_kw) -> dict:
    """Replay the run in blocks of steps, each block once bare and once per style,
    interleaved so that machine noise hits all alike; per-step cost per style."""
    steps = _per_step_inputs(run)
    out = {"steps": len(steps), "rows": sum(len(a) for a in run.channels.values())}
    writers = {}
    for style in STYLES:
        w = writers[style] = LogWriter(os.path.join(tmpdir, f"replay_{style}.mcap"),
                                       metadata=run.metadata, viz_hz=VIZ_HZ[style], **writer_kw)
        w.declare("/timing", TIMING_DTYPE)
    per_block = {m: [] for m in ("bare",) + tuple(STYLES)}
    for i in range(0, len(steps), block):
        chunk = steps[i:i + block]
        t0 = time.perf_counter()
        for recs, pwm, st, timing in chunk:
            pass
        per_block["bare"].append((time.perf_counter() - t0) / len(chunk))
        for style, log in STYLES.items():
            w = writers[style]
            t0 = time.perf_counter()
            for recs, pwm, st, timing in chunk:
                log(w, recs, pwm, st, timing)
            per_block[style].append((time.perf_counter() - t0) / len(chunk))
    for style, w in writers.items():
        t0 = time.perf_counter()
        w.close()
        close_s = time.perf_counter() - t0
        cost = np.array(per_block[style]) - np.array(per_block["bare"])
        out[f"{style}_us_per_step_median"] = float(np.median(cost)) * 1e6
        out[f"{style}_us_per_step_min"] = float(np.min(cost)) * 1e6
        out[f"{style}_close_ms"] = close_s * 1e3
    return out


def bench_bulk(run, path, viz_hz: float = 0.0, **writer_kw) -> dict:
    t0 = time.perf_counter()
    with LogWriter(path, metadata=run.metadata, viz_hz=viz_hz, **writer_kw) as w:
        write_run(run, w)
    total_s = time.perf_counter() - t0
    rows = sum(len(a) for a in run.channels.values())
    return {"write_s": total_s, "ns_per_row": total_s / rows * 1e9}


def bench_read(path) -> dict:
    t0 = time.perf_counter()
    log = read_log(path)
    read_s = time.perf_counter() - t0
    return {"read_s": read_s, "rows": sum(len(a) for a in log.channels.values()),
            "file_mb": os.path.getsize(path) / 1e6}


def bench_flight(tmpdir: str, pairs: int, duration_s: float, scenario: str = "S1") -> dict:
    """The product's own loop: `fly --processes 1` (lockstep) in turn without a log, with
    --log --viz-hz 0 and with --log (viewable channels at 1 kHz), `pairs` times; the figure
    is the loop thread's CPU time (loop_cpu_s), so other processes on the machine do not
    inflate it, and each logged flight is compared with the unlogged one just before it."""
    from silbridge.tools.loop.flight import FlightOptions, fly_one_process

    shares = []     # the viewable channels' own CPU time / the loop's, in the same flight

    def fly(log: bool, viz_hz: float = 0.0) -> float:
        path = os.path.join(tmpdir, "flight.mcap") if log else None
        s = fly_one_process(FlightOptions(scenario=scenario, duration_s=duration_s,
                                          log_path=path, viz_hz=viz_hz), out=lambda line: None)
        if path:
            if viz_hz:
                viz_cpu_s = (read_log(path, channels=[]).end or {}).get("viz_cpu_s", 0.0)
                shares.append(viz_cpu_s / s["loop_cpu_s"])
            os.unlink(path)
        return s["loop_cpu_s"] / (s["sim_s"] * 1000.0) * 1e6   # us per 1 ms physics step

    fly(False)   # warm-up: imports, JSBSim load, caches
    base, logged, viz = [], [], []
    for _ in range(max(1, pairs)):
        base.append(fly(False))
        logged.append(fly(True))
        viz.append(fly(True, 1000.0))
    b = np.array(base)
    out = {"scenario": scenario, "pairs": len(b), "duration_s": duration_s,
           "loop_us_per_step_median": float(np.median(b)),
           "loop_us_per_step_min": float(np.min(b))}
    # Measured in place (thread CPU time around the /viz work, tools/logs/viz_log.py), so the
    # machine's noise hits the numerator and the denominator alike.
    out["viz_share_of_loop_pct_median"] = float(np.median(shares) * 100.0)
    out["viz_us_per_step_median"] = float(np.median(shares) * np.median(viz))
    for key, runs in (("", logged), ("viz_", viz)):
        g = np.array(runs)
        added = g - b
        out.update({f"{key}logged_us_per_step_median": float(np.median(g)),
                    f"{key}added_us_median": float(np.median(added)),
                    f"{key}added_pct_median": float(np.median(100.0 * added / b)),
                    f"{key}added_pct_of_best": float(100.0 * (np.min(g) - np.min(b))
                                                     / np.min(b))})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=120.0, help="synthetic run length [s]")
    ap.add_argument("--compression", default="none", choices=["none", "lz4", "zstd"])
    ap.add_argument("--batch-rows", type=int, default=1024)
    ap.add_argument("--pairs", type=int, default=6,
                    help="unlogged/logged flight pairs of the real-loop A/B (0: skip it)")
    ap.add_argument("--flight-s", type=float, default=20.0,
                    help="simulated seconds per A/B flight")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    run = synthetic_run(args.duration)
    kw = {"compression": args.compression, "batch_rows": args.batch_rows}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.mcap")
        viz_path = os.path.join(tmp, "bench_viz.mcap")
        out = {"duration_s": args.duration, **kw,
               "replay": bench_replay(run, tmp, **kw),
               "bulk": bench_bulk(run, path, **kw),
               "read": bench_read(path),
               "bulk_viz": bench_bulk(run, viz_path, viz_hz=1000.0, **kw),
               "read_viz": bench_read(viz_path)}
        if args.pairs:
            out["loop"] = bench_flight(tmp, args.pairs, args.flight_s)
    if args.json:
        print(json.dumps(out))
        return 0
    rp, bk, rd = out["replay"], out["bulk"], out["read"]
    print(f"log bench: {args.duration:.0f} s synthetic run at IMU 1 kHz ({rp['rows']} rows), "
          f"compression {args.compression}, batch {args.batch_rows} rows")
    for style, label in (("separate", "4 calls/step"), ("cycle", "write_cycle "),
                         ("cycle_viz", "+ /viz 1 kHz")):
        print(f"  replay, {label} : {rp[f'{style}_us_per_step_median']:.2f} us/step median, "
              f"{rp[f'{style}_us_per_step_min']:.2f} best block "
              f"(close: {rp[f'{style}_close_ms']:.0f} ms)")
    print(f"  bulk writes          : {bk['ns_per_row']:.0f} ns/row, {bk['write_s']*1e3:.0f} ms")
    print(f"  read back            : {rd['read_s']*1e3:.0f} ms, {rd['file_mb']:.1f} MB file")
    rv = out["read_viz"]
    print(f"  read back, with /viz : {rv['read_s']*1e3:.0f} ms, {rv['file_mb']:.1f} MB file "
          f"(bulk write {out['bulk_viz']['write_s']*1e3:.0f} ms)")
    lp = out.get("loop")
    if lp:
        print(f"  real loop A/B        : `fly --processes 1` {lp['scenario']}, {lp['pairs']} pairs "
              f"of {lp['duration_s']:.0f} s flights, loop CPU {lp['loop_us_per_step_median']:.2f}"
              f" us/step median ({lp['loop_us_per_step_min']:.2f} best)")
        print(f"    /viz work measured in place: {lp['viz_us_per_step_median']:.2f} us/step = "
              f"{lp['viz_share_of_loop_pct_median']:.1f} % of the logged loop's CPU time")
        for key, label in (("", "--log --viz-hz 0"), ("viz_", "--log (/viz 1 kHz)")):
            print(f"    + {label:18s}: +{lp[key + 'added_us_median']:.2f} us/step = "
                  f"{lp[key + 'added_pct_median']:.1f} % (median of pairs; best against "
                  f"best: {lp[key + 'added_pct_of_best']:.1f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
