"""Lockstep under CPU load: how much of its idle speed a flight keeps when other work runs.

    python -m silbridge.tools.loop.load_bench [--duration 5] [--rounds 3] [--ab] [--json]

A laptop with a browser open has busy cores. Two processes in lockstep hand
the step back and forth every millisecond of sim time; if a waiting process
burns its core (spin, sched_yield) instead of sleeping until its peer
publishes, the hand-off waits for time slices and the flight crawls. This
runs `silbridge fly` (lockstep, no MAVLink, no log) with 2 processes and, for
reference, 1 process, under three loads side by side: none, one busy loop,
two busy loops (each a `python -c "while True: pass"` process, as many as the
machine has cores at most once two run). Rounds interleave the loads, so
noise from other work on the machine hits them alike; the figure per cell is
the median over rounds of the flight's own real-time factor (sim seconds over
the wall seconds of its loop, start-up excluded).

--ab adds a column: 2 processes with the doorbells off (SILBRIDGE_NO_DOORBELL=1:
the spin / yield / sleep waits the project had before), flown in the same
rounds, so "idle speed drops by at most 5 %" is judged in one run.

Targets (issue 15): 2 processes keep >= 50 % of their idle speed with one
busy loop and >= 25 % with two. Nothing is asserted; --json prints one object.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

LOADS = (0, 1, 2)
TARGETS = {1: 0.50, 2: 0.25}


def start_busy(n: int) -> list[subprocess.Popen]:
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    time.sleep(0.3 if n else 0.0)   # let them reach the run queue
    return procs


def stop_busy(procs) -> None:
    for p in procs:
        p.kill()
    for p in procs:
        p.wait()


def fly_factor(processes: int, duration_s: float, timeout_s: float,
               doorbell: bool = True) -> float | None:
    """One lockstep flight's real-time factor (None if it failed or timed out).
    doorbell=False: the waits yield and sleep as before the futex doorbells (the A/B)."""
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--lockstep", "--no-mavlink",
           "--duration", str(duration_s), "--processes", str(processes), "--json"]
    env = dict(os.environ)
    env.pop("SILBRIDGE_NO_DOORBELL", None)
    # Our flights' segments carry our tag: their start-up reclaims only our own leftovers.
    env.setdefault("SILBRIDGE_OWNER_TAG", f"load-bench-{os.getpid()}")
    if not doorbell:
        env["SILBRIDGE_NO_DOORBELL"] = "1"
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, env=env)
    except subprocess.TimeoutExpired:
        return None
    if r.returncode != 0:
        return None
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    return float(summary["realtime_factor"])


def run(duration_s: float, rounds: int, timeout_s: float, ab: bool = False, out=print) -> dict:
    """ab: also fly 2 processes with the doorbells off (SILBRIDGE_NO_DOORBELL), as row "2yield"."""
    cells: dict[tuple, list[float]] = {}
    variants = [(2, True), (1, True)] + ([(2, False)] if ab else [])
    for rnd in range(rounds):
        for load in LOADS:
            busy = start_busy(load)
            try:
                for processes, bell in variants:
                    f = fly_factor(processes, duration_s, timeout_s, bell)
                    key = processes if bell else "2yield"
                    cells.setdefault((key, load), []).append(f if f is not None else 0.0)
                    out(f"round {rnd + 1} load {load} busy, {processes} process(es)"
                        f"{'' if bell else ' (no doorbell)'}: "
                        f"{'timeout/failed' if f is None else f'{f:.2f}x'}")
            finally:
                stop_busy(busy)
    table = {}
    for processes in (1, 2) + (("2yield",) if ab else ()):
        row = {}
        idle = statistics.median(cells[(processes, 0)])
        for load in LOADS:
            med = statistics.median(cells[(processes, load)])
            row[f"busy{load}"] = {"realtime_factor": med, "of_idle": med / idle if idle else 0.0,
                                  "all": cells[(processes, load)]}
        table[f"{processes}proc" if processes != "2yield" else "2proc_no_doorbell"] = row
    two = table["2proc"]
    targets = {f"busy{n}": {"want_of_idle": want, "got_of_idle": two[f"busy{n}"]["of_idle"],
                            "met": two[f"busy{n}"]["of_idle"] >= want}
               for n, want in TARGETS.items()}
    res = {"duration_s": duration_s, "rounds": rounds, "table": table, "targets": targets}
    if ab:   # idle speed with the doorbells against without: the "no more than 5 % slower" check
        old = table["2proc_no_doorbell"]["busy0"]["realtime_factor"]
        res["idle_doorbell_vs_yield"] = two["busy0"]["realtime_factor"] / old if old else None
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=5.0, help="sim seconds per flight")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=120.0,
                    help="wall seconds one flight may take before it counts as 0x")
    ap.add_argument("--ab", action="store_true",
                    help="also fly 2 processes with the doorbells off (the waits before issue 15)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    log = (lambda s: print(s, file=sys.stderr)) if args.json else print
    res = run(args.duration, args.rounds, args.timeout, args.ab, out=log)
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"lockstep real-time factor, median of {args.rounds} rounds "
          f"({args.duration:g} s sim each)")
    cols = ["1proc", "2proc"] + (["2proc_no_doorbell"] if args.ab else [])
    heads = {"1proc": "1 process", "2proc": "2 processes", "2proc_no_doorbell": "2, no doorbell"}
    print(f"{'background load':<18}" + "".join(f"{heads[c]:>18}" for c in cols))
    for load in LOADS:
        label = "none" if load == 0 else f"{load} busy loop{'s' if load > 1 else ''}"
        cells = [res["table"][c][f"busy{load}"] for c in cols]
        print(f"{label:<18}" + "".join(f"{c['realtime_factor']:>10.1f}x ({c['of_idle']:4.0%})"
                                       for c in cells))
    if args.ab:
        print(f"idle, 2 processes: doorbell / no doorbell = {res['idle_doorbell_vs_yield']:.3f}")
    for key, t in res["targets"].items():
        print(f"target 2 processes, {key}: >= {t['want_of_idle']:.0%} of idle: "
              f"{t['got_of_idle']:.0%} {'met' if t['met'] else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
