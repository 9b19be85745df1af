"""The nav suite's table: per plan, per metric, per controller the mean and the median over
the runs that flew (n of N said), and which runs did not fly and why; then ours against each
other controller paired by seed (tools/benchmark/paired_stats.py: the median difference, its
bootstrap interval and the verdict), where a run that did not fly leaves its seed unpaired.

`summarize(results)` is the JSON (`bench --suite nav --json`, nav.json); `markdown(summary)`
the printed table and the report's (tools/benchmark/nav/report.py).
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from silbridge.tools.benchmark.nav.campaign import FC_LABELS, finite
from silbridge.tools.benchmark.nav.plans import PLANS
from silbridge.tools.benchmark.paired_stats import Paired, cells, header, method_line, paired

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
# Lower is better for every nav metric but the peak speed, which has no better side (faster
# is not better when the plan caps the speed): shown paired, with no verdict.
NO_BETTER = {"peak_speed_m_s"}
BASE = "ours"


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
        entry["paired"] = _paired(mine, plan.kind, fcs)
        out[name] = entry
    return _clean(out)


def _paired(mine, kind: str, fcs: list[str]) -> dict:
    """{fc: {key: Paired.as_dict()}}: ours against each other controller, by seed; a run
    that did not fly (status not ok) gives no value, so its seed is listed as unpaired."""
    if BASE not in fcs:
        return {}

    def by_seed(fc, key):
        return {r.seed: r.metrics.get(key) for r in mine if r.fc == fc and r.status == "ok"}
    return {fc: {key: paired(by_seed(BASE, key), by_seed(fc, key),
                             None if key in NO_BETTER else "lower").as_dict()
                 for key, _ in METRICS[kind]}
            for fc in fcs if fc != BASE}


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
    for fc in (fc for fc in fcs if fc != BASE and BASE in fcs):
        text += "\n\n" + paired_markdown(summary, fc)
    return text


def _unit(label: str) -> str:
    """'overshoot, worst leg [m]' -> 'm'."""
    return label.rsplit("[", 1)[-1].rstrip("]") if "[" in label else ""


def paired_markdown(summary: dict, fc: str) -> str:
    """Ours against fc, paired by seed: one row per plan and metric, unpaired seeds below."""
    name = FC_LABELS[fc]
    lines = [f"**Ours against {name}, paired by seed**", "",
             "| " + " | ".join(["plan", "metric"] + header("ours", name)) + " |",
             "|---|---|---|---|---|---|---|"]
    notes = []
    for plan, e in summary.items():
        labels = dict(METRICS[PLANS[plan].kind])
        for key, d in (e.get("paired") or {}).get(fc, {}).items():
            p = Paired.from_dict(d)
            lines.append("| " + " | ".join([plan, labels[key]]
                                           + cells(p, "{:.3g}", _unit(labels[key]))) + " |")
            for who, seeds in ((BASE, p.unpaired_a), (name, p.unpaired_b)):
                if seeds:
                    notes.append(f"- {plan} {labels[key]}: seed {', '.join(map(str, seeds))} "
                                 f"has a value for {who} only: not paired")
    text = "\n".join(lines + ["", method_line("ours", name)])
    return text + ("\n\n" + "\n".join(notes) if notes else "")
