"""The ablation's verdicts: each variant against the full controller, paired by seed.

Every variant of `silbridge ablate` flies the same seeds (run i on seed + i), so the effect of
switching a feature off is measured per seed, variant - full, and judged by the one rule of
tools/benchmark/paired_stats.py (median, its 95 % bootstrap interval, the verdict), as Table 1
judges ours against ArduCopter. Read a verdict as what switching the feature off does:
"loses by X" is what the feature earns on that metric, "at or below" says the variant without
it is no worse, "tie" that the runs cannot tell.

The per-run figures are kept beside the verdicts (`runs` in ablation.json), so `verdicts` and
`markdown` rebuild the table from that file alone, or from the rows of several campaigns
flown on different seeds, joined.
"""

from __future__ import annotations

import math
import numbers

from silbridge.tools.benchmark.paired_stats import (Paired, diff_text, method_dict, paired,
                                                    verdict_text, LEVEL)
from silbridge.tools.benchmark.table1_compare import BETTER

BASE = "full"
# The metrics the ablation judges, in the order of its tables: Table 1's four, then the
# noise metrics the vibration scenarios are about (docs/reference/metrics.md). Three
# significant digits, not Table 1's fixed decimals: a feature's effect can be a thousandth of
# a unit and still be consistent on every seed, and "loses by 0.000" would hide it.
METRICS = (
    ("pwm_pp_us", "p-p", "us", "{:.3g}"),
    ("sat_pct", "sat", "%", "{:.3g}"),
    ("att_rms_deg", "RMS", "deg", "{:.3g}"),
    ("att_p95_deg", "P95", "deg", "{:.3g}"),
    ("gyro_noise_dps", "gyro noise", "deg/s", "{:.3g}"),
    ("dterm_noise_us", "D-term noise", "us", "{:.3g}"),
    ("motor_noise_us", "motor noise", "us", "{:.3g}"),
)


def run_rows(results, scenario_of) -> list[dict]:
    """One JSON row per finished run: variant, scenario, seed and its numeric metrics."""
    rows = []
    for r in results:
        # NaN (a metric the run's log cannot give) becomes null: ablation.json stays JSON.
        metrics = {k: float(v) if math.isfinite(v) else None for k, v in r.metrics.items()
                   if isinstance(v, numbers.Real) and not isinstance(v, bool)}
        rows.append({"variant": r.spec.variant, "scenario": scenario_of(r),
                     "seed": int(r.spec.seed), "metrics": metrics})
    return rows


def _series(rows, variant: str, scenario: str, key: str) -> dict:
    return {row["seed"]: row["metrics"].get(key) for row in rows
            if row["variant"] == variant and row["scenario"] == scenario}


def verdicts(rows: list[dict], base: str = BASE) -> dict:
    """{variant: {scenario: {metric: Paired.as_dict() + "text"}}}, each variant - base."""
    variants = [v for v in dict.fromkeys(row["variant"] for row in rows) if v != base]
    scenarios = list(dict.fromkeys(row["scenario"] for row in rows))
    out: dict = {}
    for v in variants:
        out[v] = {}
        for sc in scenarios:
            out[v][sc] = {}
            for key, _label, unit, fmt in METRICS:
                p = paired(_series(rows, v, sc, key), _series(rows, base, sc, key), BETTER[key])
                out[v][sc][key] = p.as_dict() | {"text": verdict_text(p, fmt, unit)}
    return out


def base_medians(rows: list[dict], base: str = BASE) -> dict:
    """{scenario: {metric: the base variant's median over its runs, or None}}."""
    out: dict = {}
    for sc in dict.fromkeys(row["scenario"] for row in rows):
        out[sc] = {}
        for key, *_ in METRICS:
            vals = sorted(v for v in _series(rows, base, sc, key).values()
                          if isinstance(v, numbers.Real) and math.isfinite(v))
            n = len(vals)
            out[sc][key] = None if not n else (
                vals[n // 2] if n % 2 else 0.5 * (vals[n // 2 - 1] + vals[n // 2]))
    return out


# The verdicts-only table at the top (what the README shows): the metrics a reader decides on.
GLANCE = ("pwm_pp_us", "att_rms_deg", "att_p95_deg", "gyro_noise_dps", "motor_noise_us")


def glance_markdown(judged: dict) -> str:
    """One row per variant, one column per scenario and GLANCE metric: the verdict only."""
    if not judged:
        return ""
    labels = {key: label for key, label, _u, _f in METRICS}
    first = next(iter(judged.values()))
    cols = [(sc, key) for sc in first for key in GLANCE if _has_values(judged, key)]
    head = ["variant"] + [f"{sc} {labels[key]}" for sc, key in cols]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for v, per_sc in judged.items():
        lines.append("| " + " | ".join([v] + [per_sc[sc][key]["text"] for sc, key in cols])
                     + " |")
    return "\n".join(lines) + "\n"


def _has_values(per_variant: dict, key: str) -> bool:
    return any(m[key]["n"] > 0 for sc in per_variant.values() for m in sc.values())


def markdown(rows: list[dict], judged: dict, base: str = BASE) -> str:
    """One table per metric: variants down, scenarios across; each cell the median of
    variant - base with its interval, then the verdict. A metric no run carries is left out."""
    medians = base_medians(rows, base)
    scenarios = list(medians)
    seeds = sorted({row["seed"] for row in rows if row["variant"] == base})
    lines = [f"**Ablation, paired by seed**: each variant minus the {base} controller on the "
             f"same seed ({len(seeds)} seeds: {', '.join(map(str, seeds))}); median of the "
             f"differences [{LEVEL:.0%} bootstrap interval], and the verdict on the variant "
             f"(\"loses by X\": switching that off costs X)", "", glance_markdown(judged)]
    for key, label, unit, fmt in METRICS:
        if not judged or not _has_values(judged, key):
            continue
        head = ["variant"] + [f"{sc} Δ{label}" for sc in scenarios]
        lines += [f"*{label} ({unit})*", "", "| " + " | ".join(head) + " |",
                  "|" + "---|" * len(head)]
        base_row = [f"{base} (median)"] + [
            "n/a" if medians[sc][key] is None else fmt.format(medians[sc][key])
            for sc in scenarios]
        lines.append("| " + " | ".join(base_row) + " |")
        for v, per_sc in judged.items():
            cells = [v]
            for sc in scenarios:
                p = Paired.from_dict(per_sc[sc][key])
                cells.append(f"{diff_text(p, fmt)}: {verdict_text(p, fmt, unit)}"
                             if p.n else "n/a")
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def payload(rows: list[dict], base: str = BASE) -> dict:
    """The JSON beside the table: method, per-run rows, verdicts."""
    return {"method": method_dict(), "base": base, "runs": rows,
            "paired": verdicts(rows, base)}
