"""Table 1: mean and standard deviation of each metric per scenario, with the
paper's figures beside ours (Kim et al., Table 1; AirSim, their SIL FC).

JSON shape (fixed by the benchmark issue; "comparison" added when the runs are of several
controllers, with the medians):
  {"scenarios": {name: {metric: {"mean": x, "std": s, "n": n}}},
   "comparison": tools/benchmark/table1_compare.py compare_fcs(), ...}
Standard deviation is the sample standard deviation (ddof=1), 0 for n = 1.
Mean +- std is the paper's form; a claim that one controller is at or below another comes
from the paired comparison printed under the table, never from these means.
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.tools.benchmark.table1_compare import comparison_markdown, compare_fcs

# (metric key, row label, unit, format)
ROWS = [
    ("pwm_pp_us", "p-p", "us", "{:.1f}"),
    ("sat_pct", "sat", "%", "{:.2f}"),
    ("att_rms_deg", "RMS", "deg", "{:.3f}"),
    ("att_p95_deg", "P95", "deg", "{:.3f}"),
    ("gyro_noise_dps", "gyro noise", "deg/s", "{:.3f}"),
    ("gyro_in_noise_dps", "gyro noise in", "deg/s", "{:.3f}"),
    ("dterm_noise_us", "D-term noise", "us", "{:.2f}"),
    ("motor_noise_us", "motor noise", "us", "{:.2f}"),
    ("yaw_rate_rad_s", "yaw rate", "rad/s", "{:.4f}"),
    ("cp_us", "cp", "us", "{:.2f}"),
    ("cr_us", "cr", "us", "{:.2f}"),
    ("cy_us", "cy", "us", "{:.2f}"),
    ("latency_ms", "latency p50", "ms", "{:.4f}"),
    ("jitter_ms", "jitter p99", "ms", "{:.4f}"),
]

# The report's second table: the attitude error scored both ways (tools/benchmark/att_scoring.py) and
# the speed of the runs.
SCORING_ROWS = [
    ("att_rms_cmd_deg", "RMS vs command", "deg", "{:.3f}"),
    ("att_p95_cmd_deg", "P95 vs command", "deg", "{:.3f}"),
    ("att_rms_target_deg", "RMS vs FC target", "deg", "{:.3f}"),
    ("att_p95_target_deg", "P95 vs FC target", "deg", "{:.3f}"),
    ("realtime_factor", "speed", "x real time", "{:.1f}"),
]

# The paper's Table 1 (S1 hover, S2 gyro bias, S3 dynamic accel, S4 aggressive tilt).
PAPER = {
    "S1": {"pwm_pp_us": 46, "sat_pct": 0, "att_rms_deg": 1.227, "att_p95_deg": 0.724},
    "S2": {"pwm_pp_us": 25, "sat_pct": 0, "att_rms_deg": 2.040, "att_p95_deg": 0.636},
    "S3": {"pwm_pp_us": 26, "sat_pct": 0, "att_rms_deg": 1.748, "att_p95_deg": 1.515},
    "S4": {"pwm_pp_us": 3, "sat_pct": 0, "att_rms_deg": 0.440, "att_p95_deg": 0.734},
}


def scenario_key(name: str) -> str:
    return name.rsplit("/", 1)[-1].removesuffix(".toml")


def aggregate(results, group=lambda r: scenario_key(r.spec.scenario)) -> dict:
    """Results -> {"scenarios": {name: {metric: {mean, std, n}}}}, and
    "comparison" (paired by seed, per scenario) when the results are of ours and at least
    one other controller (spec.fc)."""
    groups: dict[str, list] = {}
    for r in results:
        groups.setdefault(group(r), []).append(r.metrics)
    table = {}
    for name, rows in groups.items():
        keys = [k for k in rows[0] if isinstance(rows[0][k], (int, float))
                and not isinstance(rows[0][k], bool)]
        table[name] = {}
        for k in keys:
            vals = np.array([row.get(k) for row in rows if row.get(k) is not None], dtype=float)
            vals = vals[np.isfinite(vals)]
            n = int(len(vals))
            table[name][k] = {
                "mean": float(vals.mean()) if n else None,
                "std": float(vals.std(ddof=1)) if n > 1 else (0.0 if n else None),
                "n": n,
            }
    out = {"scenarios": table}
    comparison = compare_fcs(results, lambda r: scenario_key(r.spec.scenario))
    if comparison is not None:
        out["comparison"] = comparison
    return out


def _num(fmt: str, v: float) -> str:
    """fmt.format(v), without the sign of a value that rounds to zero ("-0.00" -> "0.00")."""
    text = fmt.format(v)
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def _cell(stat: dict | None, fmt: str) -> str:
    if not stat or stat.get("mean") is None:
        return "n/a"
    m, s = stat["mean"], stat["std"]
    if s is None or (isinstance(s, float) and math.isnan(s)):
        return _num(fmt, m)
    return f"{_num(fmt, m)} ± {_num(fmt, s)}"


def markdown(table: dict, *, paper: bool = True, title: str = "Table 1", rows=None) -> str:
    names = list(table["scenarios"])
    n = max((next(iter(v.values()))["n"] for v in table["scenarios"].values() if v), default=0)
    head = ["metric"]
    for name in names:
        head.append(f"{name} ours")
        if paper and name in PAPER:
            head.append(f"{name} paper")
    lines = [f"**{title}** (mean ± std over n = {n} runs per scenario)", "",
             "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key, label, unit, fmt in rows or ROWS:
        row = [f"{label} ({unit})"]
        for name in names:
            row.append(_cell(table["scenarios"][name].get(key), fmt))
            if paper and name in PAPER:
                v = PAPER[name].get(key)
                row.append("" if v is None else str(v))
        lines.append("| " + " | ".join(row) + " |")
    if rows is None and table.get("comparison"):    # under Table 1 itself, not under others
        lines += ["", comparison_markdown(table["comparison"])]
    return "\n".join(lines)
