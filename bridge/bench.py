"""Micro-benchmark of Simulator.step: microseconds per physics step at several IMU rates.

    python -m silbridge.bridge.bench [--imu 1000 8000 32000] [--steps 4000] [--json]

The vehicle starts 20 m up with its motors at the open-loop hover PWM (the
airborne case: AB4 integrators, no ground contact), scenario S1 sensors. Each
figure is the best of `--reps` timed runs of `--steps` steps, timed with the
thread's CPU clock (time.thread_time), so other processes competing for the
cores do not inflate it; JSBSim's run() alone on the same state is timed the
same way for reference. Bounded: at most reps x steps steps per rate.

`--paced` also times single steps the way real time runs them, one per 1 ms of wall
clock (the bridge's Pacer: sleep, then spin), against back-to-back steps: on a shared VM
a step that waited a millisecond runs with cold caches and takes several times longer,
which is where real-time loop jitter comes from.

`--stalls S` measures the machine itself: a loop that only reads the monotonic clock for
S seconds and records every gap over 20 us (the process was not running: host or kernel
preemption, interrupts). The share of 1 ms windows hit by a gap over 50 us bounds what any
1 kHz loop's jitter p99 can be here: above 1 %, a p99 under 50 us is out of reach.
"""

from __future__ import annotations

import argparse
import json
import time

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator


def bench(imu_hz: int, steps: int, reps: int, scenario: str = "S1") -> dict:
    sc = load_scenario(scenario, overrides={"home.initial_agl_m": 20.0})
    sim = Simulator(sc, imu_hz=imu_hz)
    pwm = [sim.hover_pwm_us] * 4
    for _ in range(200):        # motors spin up, integrator switches to air
        sim.step(pwm)
    best = float("inf")
    step = sim.step
    for _ in range(reps):
        t0 = time.thread_time()
        for _ in range(steps):
            step(pwm)
        best = min(best, (time.thread_time() - t0) / steps)
    run = sim.fdm.fdm.run
    best_run = float("inf")
    for _ in range(reps):
        t0 = time.thread_time()
        for _ in range(steps):
            run()
        best_run = min(best_run, (time.thread_time() - t0) / steps)
    return {"imu_hz": imu_hz, "us_per_step": best * 1e6, "jsbsim_run_us": best_run * 1e6,
            "bridge_overhead_us": (best - best_run) * 1e6,
            "realtime_factor": sim.dt_s / best, "imu_samples_per_s": imu_hz * sim.dt_s / best}


def bench_paced(steps: int = 2000, scenario: str = "S1") -> dict:
    """Wall time of single steps back to back and paced at 1 kHz (percentiles, us)."""
    import numpy as np

    from silbridge.bridge.pacing import Pacer
    sc = load_scenario(scenario, overrides={"home.initial_agl_m": 20.0})
    sim = Simulator(sc)
    pwm = (sim.hover_pwm_us,) * 4
    for _ in range(200):
        sim.step(pwm)
    out = {}
    for name in ("back_to_back", "paced_1khz", "paced_1khz_busy_wait"):
        pacer = None if name == "back_to_back" else Pacer(sim.dt_ns,
                                                          busy_wait=name.endswith("busy_wait"))
        d = np.empty(steps)
        for k in range(steps):
            if pacer is not None:
                pacer.wait_for_step(k + 1)
            t0 = time.perf_counter_ns()
            sim.step(pwm)
            d[k] = time.perf_counter_ns() - t0
        p = np.percentile(d / 1e3, (50, 90, 99))
        out[name] = {"p50": float(p[0]), "p90": float(p[1]), "p99": float(p[2])}
    return out


def bench_stalls(seconds: float = 5.0) -> dict:
    """Gaps in a clock-reading spin loop: count per threshold and share of 1 ms windows."""
    mono = time.monotonic_ns
    t0 = prev = mono()
    t_end = t0 + int(seconds * 1e9)
    gaps, at = [], []
    while prev < t_end:
        now = mono()
        if now - prev > 20_000:
            gaps.append(now - prev)
            at.append((now - t0) // 1_000_000)
        prev = now
    windows = max(1, int(seconds * 1000))
    out = {"seconds": seconds, "max_us": max(gaps) / 1e3 if gaps else 0.0}
    for thr_us in (20, 50, 100, 500):
        hit = {w for g, w in zip(gaps, at) if g > thr_us * 1000}
        out[f"over_{thr_us}us"] = {"count": sum(g > thr_us * 1000 for g in gaps),
                                   "windows_pct": 100.0 * len(hit) / windows}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--imu", type=int, nargs="+", default=[1000, 8000, 32000])
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--paced", action="store_true",
                    help="also time steps paced at 1 kHz against back-to-back steps")
    ap.add_argument("--stalls", type=float, default=0.0, metavar="S",
                    help="also take a census of the machine's scheduling stalls for S seconds")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = [bench(hz, args.steps, args.reps) for hz in args.imu]
    paced = bench_paced() if args.paced else None
    stalls = bench_stalls(args.stalls) if args.stalls > 0 else None
    if args.json:
        print(json.dumps({"bench": "bridge.step", "results": rows, "paced_us": paced,
                          "stalls": stalls}))
    else:
        print(f"{'imu_hz':>8} {'us/step':>9} {'run() us':>9} {'bridge us':>10} {'x realtime':>11}")
        for r in rows:
            print(f"{r['imu_hz']:>8} {r['us_per_step']:>9.2f} {r['jsbsim_run_us']:>9.2f} "
                  f"{r['bridge_overhead_us']:>10.2f} {r['realtime_factor']:>11.1f}")
        if paced:
            for name, p in paced.items():
                print(f"one step, {name.replace('_', ' ')}: p50 {p['p50']:.1f} us, "
                      f"p90 {p['p90']:.1f} us, p99 {p['p99']:.1f} us (wall)")
        if stalls:
            print(f"stalls of a spinning loop over {stalls['seconds']:g} s (longest "
                  f"{stalls['max_us']:.0f} us):")
            for thr in (20, 50, 100, 500):
                st = stalls[f"over_{thr}us"]
                print(f"  > {thr:>3} us: {st['count']:>6} gaps, {st['windows_pct']:6.2f} % of "
                      f"1 ms windows")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
