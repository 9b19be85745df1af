"""Every run of the failures suite, one after another (as the nav suite: each flies against
a client on the wall clock), each scored from its ground-truth log. Run i of every plan and
autopilot flies seed + i: the same physics, noise and fault draws."""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import asdict, dataclass, field

from silbridge.tools.benchmark.failures.plans import PLANS, PlanRun, write_scenario
from silbridge.tools.benchmark.failures.runs import RUNNERS
from silbridge.tools.benchmark.failures.scoring import load_truth, score
from silbridge.tools.benchmark.failures.translate import unreachable
from silbridge.tools.benchmark.failures.watch import ALERT_SEVERITY
from silbridge.tools.benchmark.table1_compare import FC_LABELS
from silbridge.tools.logs.log_format import LogError


@dataclass
class FailureResult:
    plan: str
    fc: str
    seed: int
    status: str                  # ok, not_measured, not_in_phase, unsupported, failed
    reason: str = ""
    metrics: dict = field(default_factory=dict)
    texts: list = field(default_factory=list)     # (t_s, severity, text) after the fault
    sim_params: list = field(default_factory=list)
    log: str | None = None
    wall_s: float = 0.0
    sim_s: float = 0.0


def run_one(fc: str, name: str, seed: int, out_dir: str, **kw) -> FailureResult:
    plan = PLANS[name]
    why = unreachable(fc, plan)
    if why:
        return FailureResult(name, fc, seed, "not_measured", "; ".join(why))
    os.makedirs(os.path.join(out_dir, "logs"), exist_ok=True)
    log = os.path.join(out_dir, "logs", f"{name}-{fc}-seed{seed}.mcap")
    run = PlanRun(plan, write_scenario(plan, out_dir))
    t0 = time.monotonic()
    try:
        flight = RUNNERS[fc](run, seed=seed, log_path=log, **kw)
    except Exception as e:      # a part missing in this build (an applier, a binary): said
        if not getattr(e, "user_facing", False) and not isinstance(e, (OSError, ValueError)):
            raise
        return FailureResult(name, fc, seed, "failed", f"{type(e).__name__}: {e}",
                             wall_s=time.monotonic() - t0)
    r = FailureResult(name, fc, seed, flight.status, flight.reason, log=log,
                      wall_s=time.monotonic() - t0,
                      sim_s=flight.end_s if math.isfinite(flight.end_s) else 0.0,
                      texts=[x for x in flight.timeline.texts if x[0] >= plan.fault_on_s][:20],
                      sim_params=flight.sim_params)
    if flight.status == "ok" or (flight.status == "failed" and os.path.exists(log)):
        # A run that ended early (our FC's run stops when the vehicle crashes; an autopilot's
        # SITL may exit then) is scored from its ground truth too when the vehicle was flying
        # the phase at the fault: the outcome is the vehicle's, whatever the client heard. A
        # log in which the physics restarted is refused by load_truth.
        try:
            m = score(fc, plan, flight, load_truth(log))
        except (ValueError, OSError, LogError) as e:
            if flight.status == "ok":
                r.status, r.reason = "failed", f"scoring: {e}"
        else:
            if "not_in_phase" not in m:
                r.status, r.metrics = "ok", m
            elif flight.status == "ok":
                # what the autopilot said before the fault tells why it was not flying it
                said = [x[2] for x in flight.timeline.texts
                        if x[0] < plan.fault_on_s and x[1] <= ALERT_SEVERITY][:3]
                r.status, r.reason = "not_in_phase", m["not_in_phase"] + (
                    f"; before it: {' / '.join(said)}" if said else "")
    return r


def run_failure_campaign(fcs, plans, runs: int, base_seed: int, out_dir: str, *, speed: float,
                         arducopter=None, px4=None, params=(), keep_logs: str = "first",
                         say=lambda s: print(s, file=sys.stderr)) -> list[FailureResult]:
    """Every plan x autopilot x run, in that order; stops between runs on Ctrl-C."""
    from silbridge.tools.loop.stop_signals import STOP

    os.makedirs(os.path.join(out_dir, "logs"), exist_ok=True)
    results = []
    for name in plans:
        for fc in fcs:
            for i in range(runs):
                if STOP.requested:
                    return results
                kw = {"speed": speed, "stop": STOP}
                if fc == "ours":
                    kw["params"] = params
                elif fc == "ardupilot":
                    kw["binary"] = arducopter
                else:
                    kw["binary"] = px4
                with STOP.polling():
                    r = run_one(fc, name, base_seed + i, out_dir, **kw)
                if r.log and not (keep_logs == "all" or (keep_logs == "first" and i == 0)):
                    for path in (r.log, r.log + ".stderr"):
                        if os.path.exists(path):
                            os.remove(path)
                    r.log = None
                m = r.metrics
                say(f"bench: {name} {FC_LABELS[fc]} seed {r.seed}: {r.status}"
                    + (f" ({r.reason})" if r.reason else "")
                    + (f" detect={m['detect_s']:.3g}s action={m['action']} "
                       f"outcome={m['outcome']} dev_h={m['dev_h_m']:.3g}m "
                       f"dev_v={m['dev_v_m']:.3g}m land={m['land_dist_m']:.3g}m "
                       f"disarm={m['disarm']} {m['disarm_s']:.3g}s by={m['detected_by']!r}"
                       if m else "")
                    + f" [{r.wall_s:.0f} s wall]")
                results.append(r)
    return results


def result_dicts(results) -> list[dict]:
    def clean(x):
        if isinstance(x, float):
            return x if math.isfinite(x) else None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        return x
    return [clean(asdict(r)) for r in results]
