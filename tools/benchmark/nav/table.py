"""The nav suite's table: per plan, per metric, per controller the mean and the median over
the runs that flew (n of N said), and which runs did not fly and why.

`summarize(results)` is the JSON (`bench --suite nav --json`, nav.json); `markdown(summary)`
the printed table and the report's (tools/benchmark/nav/report.py).
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from silbridge.tools.benchmark.nav.campaign import FC_LABELS, finite
from silbridge.tools.benchmark.nav.plans import PLANS

# (key, label with unit) of each plan kind's metrics, in table order.
METRICS = {
    "goto": [("overshoot_m", "overshoot, worst leg [m]"),
             ("arrive_s", "time to arrive within 1 m, mean of legs [s]"),
             ("peak_speed_m_s", "peak horizontal speed [m/s]")],
    "velocity": [("vel_rms_m_s", "velocity error RMS [m/s]"),
                 ("yaw_rms_deg", "yaw error RMS [deg]"),
                 ("yaw_end_deg", "yaw error at leg end, worst leg [deg]")],
    "mission": [("time_s", "time to complete [s]"),
                ("xtrack_rms_m", "cross-track error RMS [m]"),
                ("xtrack_max_m", "cross-track error max [m]"),
                ("accel_max_m_s2", "peak horizontal acceleration [m/s^2]"),
                ("jerk_rms_m_s3", "horizontal jerk RMS [m/s^3]")],
}


def _clean(x):
    """JSON-safe: NaN and inf become null, recursively."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def summarize(results, fcs: list[str]) -> dict:
    """{plan: {"title", "metrics": {key: {fc: {mean, median, n}}}, "runs": {fc: {status:
    count}}, "reasons": {fc: [distinct reasons]}}}."""
    out = {}
    for name in dict.fromkeys(r.plan for r in results):
        plan = PLANS[name]
        mine = [r for r in results if r.plan == name]
        entry = {"title": plan.title, "metrics": {}, "runs": {}, "reasons": {}}
        for fc in fcs:
            rs = [r for r in mine if r.fc == fc]
            entry["runs"][fc] = dict(Counter(r.status for r in rs))
            entry["reasons"][fc] = list(dict.fromkeys(r.reason for r in rs if r.reason))
        for key, _ in METRICS[plan.kind]:
            cell = {}
            for fc in fcs:
                v = finite(r.metrics.get(key) for r in mine if r.fc == fc and r.status == "ok")
                cell[fc] = {"mean": float(np.mean(v)) if len(v) else None,
                            "median": float(np.median(v)) if len(v) else None,
                            "n": int(len(v))}
            entry["metrics"][key] = cell
        out[name] = entry
    return _clean(out)


def _fmt(cell: dict) -> str:
    if cell["mean"] is None:
        return "-"
    return f"{cell['mean']:.3g} / {cell['median']:.3g}"


def markdown(summary: dict, fcs: list[str], runs: int) -> str:
    """One table: a row per plan and metric, mean / median per controller; then a row per
    plan of flown / planned runs, and the reasons of the runs that did not fly."""
    head = ["plan", "metric"] + [f"{FC_LABELS[fc]} mean / median" for fc in fcs]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    notes = []
    for name, e in summary.items():
        kind = PLANS[name].kind
        labels = dict(METRICS[kind])
        runs_row = [f"{e['runs'][fc].get('ok', 0)} of {runs}" for fc in fcs]
        lines.append(f"| {name} | runs flown | " + " | ".join(runs_row) + " |")
        for key, cell in e["metrics"].items():
            lines.append(f"| {name} | {labels[key]} | "
                         + " | ".join(_fmt(cell[fc]) for fc in fcs) + " |")
        for fc in fcs:
            for reason in e["reasons"][fc]:
                notes.append(f"- {name} {FC_LABELS[fc]}: {reason}")
    text = "\n".join(lines)
    if notes:
        text += "\n\nRuns that did not fly the plan:\n" + "\n".join(notes)
    return text
