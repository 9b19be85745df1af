"""Every run of the nav suite, one after another, each scored from its ground-truth log.

Runs are sequential: each one flies in real time (times --speed) against a MAVLink client
whose reaction time is wall time, so two at once on a loaded machine would change what the
client sees. Run i of every plan and every controller uses seed + i: the same wind, the
same turbulence, the same sensor noise draws on the physics side.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from silbridge.tools.benchmark.nav.plans import PLANS, Plan
from silbridge.tools.benchmark.nav.scoring import (Track, score_goto, score_mission,
                                                   score_velocity, yaw_from_quat)
from silbridge.tools.benchmark.nav.scripts import Flight
from silbridge.tools.benchmark.table1_compare import FC_LABELS  # noqa: F401 (declared there)
from silbridge.tools.logs.log_format import LogError


@dataclass
class NavResult:
    plan: str
    fc: str
    seed: int
    status: str                       # ok, unsupported, failed
    reason: str = ""
    metrics: dict = field(default_factory=dict)
    log: str | None = None
    wall_s: float = 0.0
    sim_s: float = 0.0


def load_track(log_path: str) -> Track:
    """The true trajectory of a run log (/gt_nav, /gt_att; both written every physics step)."""
    from silbridge.tools.logs.log_reader import read_log

    log = read_log(log_path, channels=["/gt_nav", "/gt_att"])
    nav, att = log.channels.get("/gt_nav"), log.channels.get("/gt_att")
    if nav is None or att is None or not len(nav):
        raise ValueError(f"{log_path}: no ground truth (/gt_nav, /gt_att) in the log")
    n = min(len(nav), len(att))
    nav, att = nav[:n], att[:n]
    pos = nav["pos_ned_m"].astype(float)
    return Track(t_s=nav["sim_ns"] * 1e-9, pos_ne=pos[:, :2], alt_m=-pos[:, 2],
                 vel_ne=nav["vel_ned_m_s"][:, :2].astype(float),
                 yaw_rad=yaw_from_quat(att["q_wxyz"]))


def score_flight(plan: Plan, flight: Flight, track: Track) -> dict:
    """The plan's metrics of a flight that went through (status ok)."""
    if plan.kind == "goto":
        m = score_goto(track, [(g.north_m, g.east_m) for g in plan.steps], flight.sent_s,
                       flight.end_s)
        m.pop("legs")
        return m
    if plan.kind == "velocity":
        return score_velocity(track, plan.steps, flight.sent_s, flight.end_s)
    return score_mission(track, plan.steps, flight.sent_s[0], flight.end_s)


def fly_one(fc: str, plan: Plan, seed: int, log_path: str, *, speed: float, arducopter=None,
            px4=None, params=(), stop=None) -> Flight:
    if fc == "ours":
        from silbridge.tools.benchmark.nav.run_ours import fly_ours
        return fly_ours(plan, seed=seed, log_path=log_path, speed=speed, params=params,
                        stop=stop)
    if fc == "ardupilot":
        from silbridge.tools.benchmark.nav.run_ardupilot import fly_ardupilot
        return fly_ardupilot(plan, seed=seed, log_path=log_path, speed=speed, binary=arducopter,
                             stop=stop)
    from silbridge.tools.benchmark.nav.run_px4 import fly_px4
    return fly_px4(plan, seed=seed, log_path=log_path, speed=speed, binary=px4, stop=stop)


def run_nav_campaign(fcs, plans, runs: int, base_seed: int, out_dir: str, *, speed: float,
                     arducopter=None, px4=None, params=(),
                     keep_logs: str = "first", say=lambda s: print(s, file=sys.stderr)
                     ) -> list[NavResult]:
    """Every plan x controller x run, in that order; stops between runs on Ctrl-C."""
    from silbridge.tools.loop.stop_signals import STOP

    os.makedirs(os.path.join(out_dir, "logs"), exist_ok=True)
    results = []
    for name in plans:
        for fc in fcs:
            for i in range(runs):
                if STOP.requested:
                    return results
                seed = base_seed + i
                log = os.path.join(out_dir, "logs", f"{name}-{fc}-seed{seed}.mcap")
                ours = fc == "ours"
                with STOP.polling():   # Ctrl-C ends the flight; its log is still closed
                    r = run_one(fc, PLANS[name], seed, log, speed=speed, arducopter=arducopter,
                                px4=px4, params=params if ours else (), stop=STOP)
                if not (keep_logs == "all" or (keep_logs == "first" and i == 0)):
                    for path in (log, log + ".stderr"):
                        if os.path.exists(path):
                            os.remove(path)
                    r.log = None
                say(f"bench: {name} {FC_LABELS[fc]} seed {seed}: {r.status}"
                    + (f" ({r.reason})" if r.reason else "")
                    + "".join(f" {k}={v:.3g}" for k, v in r.metrics.items())
                    + f" [{r.wall_s:.0f} s wall]")
                results.append(r)
    return results


def run_one(fc: str, plan: Plan, seed: int, log: str, **kw) -> NavResult:
    """One flight, scored from its log when it flew the plan."""
    t0 = time.monotonic()
    flight = fly_one(fc, plan, seed, log, **kw)
    r = NavResult(plan.name, fc, seed, flight.status, flight.reason, log=log,
                  wall_s=time.monotonic() - t0,
                  sim_s=flight.end_s if math.isfinite(flight.end_s) else 0.0)
    if flight.status == "ok":
        try:
            r.metrics = score_flight(plan, flight, load_track(log))
        except (ValueError, OSError, LogError) as e:
            r.status, r.reason = "failed", f"scoring: {e}"
    return r


def result_dicts(results: list[NavResult]) -> list[dict]:
    return [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
             for k, v in asdict(r).items()} for r in results]


def finite(values) -> np.ndarray:
    a = np.asarray([v for v in values if v is not None], dtype=float)
    return a[np.isfinite(a)]
