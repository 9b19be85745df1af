"""Table 1's controllers compared: ours against ArduCopter and PX4, paired by seed.

`bench --fc ours,ardupilot[,px4]` flies run i of every controller on seed + i; each of its
scenarios gets, per other controller and per metric with a better direction, the paired
comparison of tools/benchmark/paired_stats.py (medians, the median difference ours - theirs
with its bootstrap interval, the verdict). Table 1 itself stays mean +- std, the paper's form;
what the docs and the README may claim comes from the verdicts here.

A metric the other controller's log does not carry (our filtered gyro, the D term) is listed
as not compared rather than printed as a row of n/a.
"""

from __future__ import annotations

import math
import numbers

from silbridge.tools.benchmark.paired_stats import (Paired, cells, header, method_dict,
                                                    method_line, paired, verdict_text)

FC_LABELS = {"ours": "ours", "ardupilot": "ArduCopter", "px4": "PX4"}

# The direction in which a metric is better; None: shown, no verdict (the IMU input is not
# the controller's merit, but the filtered figures are read against it).
# Left out: yaw rate (a signed mean, no better side), cp/cr/cy (ours only), latency and
# jitter (a different quantity for a foreign autopilot's link, docs/reference/metrics.md).
BETTER = {
    "pwm_pp_us": "lower", "sat_pct": "lower", "att_rms_deg": "lower", "att_p95_deg": "lower",
    "gyro_noise_dps": "lower", "dterm_noise_us": "lower", "motor_noise_us": "lower",
    "gyro_in_noise_dps": None,
    "att_rms_target_deg": "lower", "att_p95_target_deg": "lower",
}


def _fc(r) -> str:
    return getattr(r.spec, "fc", "ours")


def _compared_rows():
    from silbridge.tools.benchmark.table1 import ROWS, SCORING_ROWS
    return [row for row in ROWS + SCORING_ROWS if row[0] in BETTER]


def _by_seed(rows: dict, key: str) -> dict:
    return {seed: m.get(key) for seed, m in rows.items()}


def _has_values(rows: dict, key: str) -> bool:
    return any(isinstance(v, numbers.Real) and math.isfinite(v)
               for v in _by_seed(rows, key).values())


def _one(sc: str, base: str, fc: str, ours: dict, theirs: dict) -> dict:
    """One scenario, base (ours) against one other controller."""
    metrics, missing = {}, []
    for key, label, unit, fmt in _compared_rows():
        if not _has_values(theirs, key) or not _has_values(ours, key):
            missing.append(key)
            continue
        p = paired(_by_seed(ours, key), _by_seed(theirs, key), BETTER[key])
        metrics[key] = p.as_dict() | {"text": verdict_text(p, fmt, unit)}
    return {"scenario": sc, "fc": fc, "label": FC_LABELS.get(fc, fc), "metrics": metrics,
            "not_compared": missing,
            "unpaired_runs": {base: sorted(set(ours) - set(theirs)),
                              fc: sorted(set(theirs) - set(ours))}}


def compare_fcs(results, scenario_of, base: str = "ours", side_of=_fc) -> dict | None:
    """results of several controllers -> {"method", "base", "comparisons": [...]}, or None
    when they are not base and at least one other. scenario_of(result) -> scenario name;
    side_of(result) -> which side it is on (the controller; an ablation could pass the
    variant, with base "full")."""
    runs: dict = {}                                   # (scenario, side) -> {seed: metrics}
    for r in results:
        runs.setdefault((scenario_of(r), side_of(r)), {})[int(r.spec.seed)] = r.metrics
    fcs = list(dict.fromkeys(fc for _sc, fc in runs))
    if base not in fcs or len(fcs) < 2:
        return None
    out = []
    for sc in dict.fromkeys(sc for sc, _fc in runs):
        for fc in fcs:
            if fc != base and (sc, base) in runs and (sc, fc) in runs:
                out.append(_one(sc, base, fc, runs[(sc, base)], runs[(sc, fc)]))
    return {"method": method_dict(), "base": base, "comparisons": out}


def _unpaired_notes(c: dict, base: str, labels: dict) -> list[str]:
    notes = []
    for fc, seeds in c["unpaired_runs"].items():
        if seeds:
            notes.append(f"- {c['scenario']}: seed {', '.join(map(str, seeds))} flown by "
                         f"{FC_LABELS.get(fc, fc)} only: not paired")
    for key, m in c["metrics"].items():
        for side, fc in (("unpaired_a", base), ("unpaired_b", c["fc"])):
            extra = sorted(set(m[side]) - set(c["unpaired_runs"].get(fc, ())))
            if extra:
                notes.append(f"- {c['scenario']} {labels[key]}: seed "
                             f"{', '.join(map(str, extra))} has a value for "
                             f"{FC_LABELS.get(fc, fc)} only: not paired")
    return notes


def comparison_markdown(comp: dict | None) -> str:
    """The paired tables, one per other controller, with the unpaired runs below."""
    if not comp or not comp["comparisons"]:
        return ""
    rows = {key: (label, unit, fmt) for key, label, unit, fmt in _compared_rows()}
    labels = {key: label for key, (label, _u, _f) in rows.items()}
    base = comp["base"]
    ours = FC_LABELS.get(base, base)
    parts = []
    for fc in dict.fromkeys(c["fc"] for c in comp["comparisons"]):
        name = FC_LABELS.get(fc, fc)
        lines = [f"**{ours.capitalize()} against {name}, paired by seed**", "",
                 "| " + " | ".join(["scenario", "metric"] + header(ours, name)) + " |",
                 "|---|---|---|---|---|---|---|"]
        notes = []
        for c in (c for c in comp["comparisons"] if c["fc"] == fc):
            for key, m in c["metrics"].items():
                label, unit, fmt = rows[key]
                row = [c["scenario"], f"{label} ({unit})"]
                row += cells(Paired.from_dict(m), fmt, unit)
                lines.append("| " + " | ".join(row) + " |")
            if c["not_compared"]:
                notes.append(f"- {c['scenario']}: not compared (the log of {name} or {ours} "
                             f"does not carry it): "
                             + ", ".join(labels[k] for k in c["not_compared"]))
            notes += _unpaired_notes(c, base, labels)
        parts.append("\n".join(lines + ["", method_line(ours, name)] + ([""] + notes
                                                                         if notes else [])))
    return "\n\n".join(parts)
