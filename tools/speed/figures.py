"""From the runs of each case to the figures `silbridge speed` prints: the real-time factor's
median, min, max and worst-vs-median spread, wall and CPU time per physics step, the ratios to
bare JSBSim and to ArduCopter's own physics, and the issue's targets beside the measured values.

A ratio divides medians: the runs are interleaved, so drift of the machine hits both sides of
a ratio alike. The targets are never a pass/fail status: absolute speeds differ 2x between
machines of this kind, and the ratios are what the issue compares.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass


@dataclass(frozen=True)
class Target:
    case: str           # a case name (tools/speed/cases.py)
    figure: str         # a key of that case's figures
    op: str             # ">=" or "<="
    value: float
    source: str         # where the target is written

    def met(self, measured: float) -> bool:
        return measured >= self.value if self.op == ">=" else measured <= self.value


# Issue 25's targets, ratios in one run on the reference 2-core machine.
TARGETS = (
    Target("fly1", "of_jsbsim", ">=", 0.8, "issue 25: one process >= 0.8 of bare JSBSim"),
    Target("fly2", "of_jsbsim", ">=", 0.7, "issue 25: two processes, idle, >= 0.7 of bare "
                                           "JSBSim"),
    Target("fly2", "worst_below_median", "<=", 0.2, "issue 25: two processes, the worst of "
                                                    "5 runs within 20 % of the median"),
    Target("campaign2", "of_single_run", ">=", 1.6, "issue 25: the campaign on 2 jobs >= 1.6x "
                                                    "a single run's speed"),
)


def _spread(values: list[float]) -> dict:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def case_figures(runs: list[dict], physics_hz: float) -> dict:
    """Figures of one case from its runs ({'realtime_factor', 'loop_cpu_s', 'sim_s'} each)."""
    rtf = [r["realtime_factor"] for r in runs]
    # Wall time per physics step from each run's own factor: sim time per step over the factor.
    wall_us = [1e6 / (physics_hz * x) for x in rtf]
    out = {"realtime_factor": _spread(rtf),
           # How far the slowest run falls below the median: 0.2 = 20 % slower.
           "worst_below_median": 1.0 - min(rtf) / statistics.median(rtf),
           "wall_us_per_step": _spread(wall_us), "loop_cpu_s": None, "cpu_us_per_step": None}
    if all(r["loop_cpu_s"] is not None for r in runs):
        out["loop_cpu_s"] = _spread([r["loop_cpu_s"] for r in runs])
        out["cpu_us_per_step"] = _spread([1e6 * r["loop_cpu_s"] / (r["sim_s"] * physics_hz)
                                          for r in runs])
    # How the flights reached JSBSim's nodes (fly --json): "c", or why the Python methods.
    nodes = sorted({r["jsbsim_nodes"] for r in runs if r.get("jsbsim_nodes")})
    if nodes:
        out["jsbsim_nodes"] = "; ".join(nodes)
    return out


def add_ratios(cases: dict[str, dict]) -> None:
    """Each case's median factor over bare JSBSim's and over ArduCopter's (None if absent)."""
    jsbsim = cases["jsbsim"]["realtime_factor"]["median"]
    ardu = cases.get("arducopter")
    ardu_x = ardu["realtime_factor"]["median"] if ardu else None
    for c in cases.values():
        x = c["realtime_factor"]["median"]
        c["of_jsbsim"] = x / jsbsim
        c["of_arducopter"] = x / ardu_x if ardu_x else None


def targets(cases: dict[str, dict]) -> list[dict]:
    """The issue's targets beside the measured values (the cases measured this time)."""
    rows = []
    for t in TARGETS:
        if t.case in cases:
            measured = cases[t.case][t.figure]
            rows.append({"case": t.case, "figure": t.figure, "measured": measured,
                         "op": t.op, "target": t.value, "met": t.met(measured),
                         "source": t.source})
    return rows


def add_campaign(cases: dict[str, dict]) -> None:
    """The campaign cases' overall factor over a single run's: the median of the runs' own
    factors in the 1-job campaign (each run alone on the machine, in the same sitting)."""
    if "campaign1" not in cases:
        return
    single = statistics.median(r["run_realtime_factor"] for r in cases["campaign1"]["runs"])
    for name in ("campaign1", "campaign2"):
        c = cases[name]
        c["single_run_x"] = single
        c["of_single_run"] = c["realtime_factor"]["median"] / single
        # what keeps it from jobs x a single run besides the runs slowing each other
        c["flying"] = statistics.median(r["flying"] for r in c["runs"])
        c["outside_flight_s"] = statistics.median(r["outside_flight_s"] for r in c["runs"])
