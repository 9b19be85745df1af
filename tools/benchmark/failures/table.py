"""The failures suite's table: per plan, the three autopilots side by side (detection,
action, outcome, deviations, landing distance: medians over the runs that flew, counts for
the words), the runs that were not measured and why; then ours against each other
autopilot paired by seed (tools/benchmark/paired_stats.py) on the numbers.

`summarize(results)` is the JSON (`--json`, failures.json); `markdown(summary)` the
printed table and the report's.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from silbridge.tools.benchmark.failures.plans import PLANS
from silbridge.tools.benchmark.paired_stats import Paired, cells, header, method_line, paired
from silbridge.tools.benchmark.table1_compare import FC_LABELS

NUMBERS = [("detect_s", "detection after the fault [s]"),
           ("dev_h_m", "worst horizontal deviation [m]"),
           ("dev_v_m", "worst vertical deviation [m]"),
           ("land_dist_m", "landing distance from the expected point [m]"),
           ("disarm_s", "disarmed after the fault [s]")]
WORDS = [("action", "action taken"), ("outcome", "outcome"), ("disarm", "disarmed")]
BASE = "ours"
NOTE_CHARS = 240       # a reason longer than this is cut in the table (failures.json has it all)


def _clean(x):
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def _median(values) -> dict:
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], float)
    return {"median": float(np.median(v)) if len(v) else None, "n": int(len(v))}


def summarize(results, fcs: list[str]) -> dict:
    out = {}
    for name in dict.fromkeys(r.plan for r in results):
        mine = [r for r in results if r.plan == name]
        e = {"title": PLANS[name].title, "runs": {}, "reasons": {}, "numbers": {}, "words": {},
             "detected_by": {}}
        for fc in fcs:
            rs = [r for r in mine if r.fc == fc]
            ok = [r for r in rs if r.status == "ok"]
            e["runs"][fc] = dict(Counter(r.status for r in rs))
            e["reasons"][fc] = list(dict.fromkeys(r.reason for r in rs if r.reason))
            for key, _ in NUMBERS:
                e["numbers"].setdefault(key, {})[fc] = _median(r.metrics.get(key) for r in ok)
            for key, _ in WORDS:
                # .get: parts flown before a word existed (merge.py) have none for it
                e["words"].setdefault(key, {})[fc] = dict(Counter(
                    r.metrics[key] for r in ok if r.metrics.get(key) is not None))
            e["detected_by"][fc] = list(dict.fromkeys(r.metrics["detected_by"] for r in ok
                                                      if r.metrics["detected_by"]))
        e["paired"] = _paired(mine, fcs)
        out[name] = e
    return _clean(out)


def _paired(mine, fcs) -> dict:
    if BASE not in fcs:
        return {}

    def by_seed(fc, key):
        return {r.seed: r.metrics.get(key) for r in mine if r.fc == fc and r.status == "ok"}
    return {fc: {key: paired(by_seed(BASE, key), by_seed(fc, key), "lower").as_dict()
                 for key, _ in NUMBERS} for fc in fcs if fc != BASE}


def _num(cell: dict) -> str:
    return "-" if cell["median"] is None else f"{cell['median']:.3g}"


def _words(counts: dict) -> str:
    if not counts:
        return "-"
    return ", ".join(f"{w} x{n}" if n > 1 else w for w, n in counts.items())


def markdown(summary: dict, fcs: list[str], runs: int) -> str:
    head = ["plan", "metric"] + [FC_LABELS[fc] for fc in fcs]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    notes = []
    for name, e in summary.items():
        lines.append(f"| {name} | runs measured | "
                     + " | ".join(f"{e['runs'][fc].get('ok', 0)} of {runs}" for fc in fcs)
                     + " |")
        for key, label in WORDS:
            lines.append(f"| {name} | {label} | "
                         + " | ".join(_words(e["words"][key][fc]) for fc in fcs) + " |")
        for key, label in NUMBERS:
            lines.append(f"| {name} | {label}, median | "
                         + " | ".join(_num(e["numbers"][key][fc]) for fc in fcs) + " |")
        for fc in fcs:
            for reason in e["reasons"][fc]:
                short = reason if len(reason) <= NOTE_CHARS else reason[:NOTE_CHARS] + " ..."
                notes.append(f"- {name} {FC_LABELS[fc]}: {short}")
            if e["detected_by"][fc]:
                notes.append(f"- {name} {FC_LABELS[fc]} detected by: "
                             + " / ".join(e["detected_by"][fc][:3]))
    text = "\n".join(lines)
    if notes:
        text += "\n\n" + "\n".join(n.replace("|", "/") for n in notes)
    for fc in (f for f in fcs if f != BASE and BASE in fcs):
        text += "\n\n" + paired_markdown(summary, fc)
    return text


def paired_markdown(summary: dict, fc: str) -> str:
    name = FC_LABELS[fc]
    lines = [f"**Ours against {name}, paired by seed** (lower is better)", "",
             "| " + " | ".join(["plan", "metric"] + header("ours", name)) + " |",
             "|---|---|---|---|---|---|---|"]
    labels = dict(NUMBERS)
    for plan, e in summary.items():
        for key, d in (e.get("paired") or {}).get(fc, {}).items():
            p = Paired.from_dict(d)
            if p.n == 0:         # nothing to pair (not measured, never landed): no row
                continue
            unit = labels[key].rsplit("[", 1)[-1].rstrip("]")
            lines.append("| " + " | ".join([plan, labels[key]] + cells(p, "{:.3g}", unit)) + " |")
    return "\n".join(lines + ["", method_line("ours", name)])
