"""Benchmark of run logging: its cost per physics step, and read-back time.

Two measurements, because a writer's cost depends on where it runs:

1. Synthetic replay: a synthetic run (tools/log_synth.py) at IMU 1 kHz is
   replayed the way the closed loop logs: per physics step the sensor and
   ground-truth records the FC consumed, its status rows, the timing row and
   the PWM records, either as four calls (`write_records`, `write`, `pack`,
   `write_records`, as tools/run_log.py does) or as one `write_cycle`. Hot
   caches, so this is the writer's floor. Also bulk writes (ns per row), file
   size and the time `read_log` takes to read every channel back.
2. Real loop A/B: the project's Simulator (S1) and FlightCore stepped in
   lockstep in this process, in blocks of steps alternately without logging,
   with the four calls and with `write_cycle`; the difference to the unlogged
   block just before is what logging adds to the loop, caches and all.
   Skipped if those parts cannot be built.

Both measurements interleave their variants block by block, so that machine
noise (other processes on the 2 cores) hits all alike, and report the median
and the best block. Nothing is asserted.

    python -m silbridge.tools.log_bench [--duration 120] [--loop-steps 30000] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np

from silbridge.shm.records import RECORD_DTYPE
from silbridge.tools.log_synth import step_slices, synthetic_run, write_run
from silbridge.tools.mcap_log import TIMING_DTYPE, LogWriter, read_log

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


STYLES = {"separate": _log_separately, "cycle": _log_cycle}


def bench_replay(run, tmpdir: str, block: int = 500, **writer_kw) -> dict:
    """Replay the run in blocks of steps, each block once bare and once per style,
    interleaved so that machine noise hits all alike; per-step cost per style."""
    steps = _per_step_inputs(run)
    out = {"steps": len(steps), "rows": sum(len(a) for a in run.channels.values())}
    writers = {}
    for style in STYLES:
        w = writers[style] = LogWriter(os.path.join(tmpdir, f"replay_{style}.mcap"),
                                       metadata=run.metadata, **writer_kw)
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


def bench_bulk(run, path, **writer_kw) -> dict:
    t0 = time.perf_counter()
    with LogWriter(path, metadata=run.metadata, **writer_kw) as w:
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


def bench_loop(path, steps: int, block: int = 500, **writer_kw) -> dict:
    """Simulator + FlightCore in lockstep, blocks alternately logged three ways."""
    try:
        from silbridge.bridge.scenario import load_scenario
        from silbridge.bridge.simulator import Simulator
        from silbridge.fc_sil.core import FlightCore
        sim = Simulator(load_scenario("S1"))
        core = FlightCore()
        core.arm()
        core.set_altitude_target(5.0)
    except Exception as exc:  # noqa: BLE001 - the loop parts are optional here
        return {"skipped": f"{type(exc).__name__}: {exc}"}
    w = LogWriter(path, metadata={}, **writer_kw)
    w.declare("/timing", TIMING_DTYPE)
    pwm_us = np.full(4, 1000, np.uint16)
    prev_ns = 0
    modes = ("none",) + tuple(STYLES)
    per_block = {m: [] for m in modes}
    for b in range(max(1, steps // (block * len(modes)))):
        for mode in modes:
            log = STYLES.get(mode)
            t0 = time.perf_counter()
            for _ in range(block):
                recs = sim.step(pwm_us)
                pwm, st = core.step_batch(recs)
                if len(pwm):
                    pwm_us = pwm["pwm_us"][-1, :4]
                # The loop measures these times for its own statistics in every mode;
                # only handing them to the writer counts as logging.
                now = time.perf_counter_ns()
                timing = (int(recs["sim_ns"][-1]), now, now, now if len(pwm) else 0,
                          now - prev_ns)
                prev_ns = now
                if log is not None:
                    log(w, recs, pwm, st, timing)
            per_block[mode].append((time.perf_counter() - t0) / block * 1e6)
    w.close()
    base = np.array(per_block["none"])
    out = {"steps": sum(len(v) for v in per_block.values()) * block,
           "loop_us_per_step_median": float(np.median(base)),
           "loop_us_per_step_min": float(np.min(base))}
    for mode in STYLES:
        # Paired with the unlogged block just before it: slow drifts in the
        # machine's load cancel out.
        added = np.array(per_block[mode]) - base
        out[f"{mode}_added_us_median"] = float(np.median(added))
        out[f"{mode}_added_pct_median"] = float(np.median(100.0 * added / base))
        out[f"{mode}_added_us_p25"] = float(np.percentile(added, 25))
        out[f"{mode}_added_pct_p25"] = float(np.percentile(100.0 * added / base, 25))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=120.0, help="synthetic run length [s]")
    ap.add_argument("--compression", default="none", choices=["none", "lz4", "zstd"])
    ap.add_argument("--batch-rows", type=int, default=1024)
    ap.add_argument("--loop-steps", type=int, default=30000,
                    help="steps of the real-loop A/B (0: skip it)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    run = synthetic_run(args.duration)
    kw = {"compression": args.compression, "batch_rows": args.batch_rows}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.mcap")
        out = {"duration_s": args.duration, **kw,
               "replay": bench_replay(run, tmp, **kw),
               "bulk": bench_bulk(run, path, **kw),
               "read": bench_read(path)}
        if args.loop_steps:
            out["loop"] = bench_loop(os.path.join(tmp, "loop.mcap"), args.loop_steps, **kw)
    if args.json:
        print(json.dumps(out))
        return 0
    rp, bk, rd = out["replay"], out["bulk"], out["read"]
    print(f"log bench: {args.duration:.0f} s synthetic run at IMU 1 kHz ({rp['rows']} rows), "
          f"compression {args.compression}, batch {args.batch_rows} rows")
    for style, label in (("separate", "4 calls/step"), ("cycle", "write_cycle ")):
        print(f"  replay, {label} : {rp[f'{style}_us_per_step_median']:.2f} us/step median, "
              f"{rp[f'{style}_us_per_step_min']:.2f} best block "
              f"(close: {rp[f'{style}_close_ms']:.0f} ms)")
    print(f"  bulk writes          : {bk['ns_per_row']:.0f} ns/row, {bk['write_s']*1e3:.0f} ms")
    print(f"  read back            : {rd['read_s']*1e3:.0f} ms, {rd['file_mb']:.1f} MB file")
    lp = out.get("loop")
    if lp and "skipped" in lp:
        print(f"  real loop A/B        : skipped ({lp['skipped']})")
    elif lp:
        print(f"  real loop A/B        : {lp['steps']} steps, loop {lp['loop_us_per_step_median']:.2f}"
              f" us/step median ({lp['loop_us_per_step_min']:.2f} min)")
        for mode in STYLES:
            print(f"    + logging ({mode:>8}): +{lp[f'{mode}_added_us_median']:.2f} us/step = "
                  f"{lp[f'{mode}_added_pct_median']:.1f} % (median of paired blocks; "
                  f"quartile 1: +{lp[f'{mode}_added_us_p25']:.2f} us = "
                  f"{lp[f'{mode}_added_pct_p25']:.1f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
