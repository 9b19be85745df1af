"""Score a parameter set the way `tune auto` judges its result, and lay several side by side.

One set is scored by Table 1 (S1 and S4 on the seeds the before/after check uses, the full
120 s protocol) and by the check sweeps (margins per axis). `tune auto` scores the
defaults, its tuned set and every `--compare FILE.parm` (e.g. the .parm `tune anchor`
writes from ArduCopter's AUTOTUNE) on the same seeds, so one command gives the whole
comparison. A set that crashes the vehicle is a result, not an error: it is reported as
such, with the seed or sweep that crashed.
"""

from __future__ import annotations

from pathlib import Path

from silbridge.fc_sil import params as P

from silbridge.tools.tune.tune_sysid import TuneError, identify

# Table 1 keys the comparison shows (scenario, metric key, label, format).
ROWS = (("S4", "att_rms_cmd_deg", "S4 attitude RMS vs the command (deg)", "{:.3f}"),
        ("S4", "att_p95_cmd_deg", "S4 attitude P95 vs the command (deg)", "{:.3f}"),
        ("S4", "att_rms_target_deg", "S4 attitude RMS vs the shaped target (deg)", "{:.3f}"),
        ("S1", "pwm_pp_us", "S1 PWM p-p (us)", "{:.2f}"),
        ("S4", "pwm_pp_us", "S4 PWM p-p (us)", "{:.1f}"),
        ("S1", "sat_pct", "S1 saturation (%)", "{:.2f}"),
        ("S4", "sat_pct", "S4 saturation (%)", "{:.2f}"))
# Parameters each column lists, so a reader sees what differs (shaping included).
SHOWN = ("ATC_RAT_RLL_P", "ATC_RAT_RLL_I", "ATC_RAT_RLL_D", "ATC_RAT_RLL_FF", "ATC_ANG_RLL_P",
         "ATC_ANG_PIT_P", "ATC_ACCEL_R_MAX", "ATC_ACCEL_P_MAX", "ATC_INPUT_TC",
         "INS_GYRO_FILTER")


def load_compare(path: str) -> tuple[str, dict]:
    """(label, {NAME: value}) from a .parm file; the label is the file's stem."""
    from silbridge.mavlink.gcs.params_file import load_parm
    return Path(path).stem, {n.upper(): float(v) for n, v in load_parm(path)}


def score_set(pool, params: dict, cfg, work: Path, tag: str) -> dict:
    """{"table": aggregate() or None, "means", "margins", "failed": reason or None}."""
    from silbridge.tools.benchmark.table1 import aggregate
    from silbridge.tools.tune.tune_auto import means, table1_runs

    out = {"table": None, "means": None, "margins": {}, "failed": None}
    try:
        out["table"] = aggregate(table1_runs(pool, params, cfg, work, tag))
        out["means"] = means(out["table"])
    except TuneError as exc:
        out["failed"] = str(exc)
    try:
        out["margins"] = {a: r.summary for a, r in
                          identify(cfg.axes, cfg.check_sweep, params, runner=pool.map).items()}
    except TuneError as exc:
        out["failed"] = out["failed"] or str(exc)
    return out


def _margin_cells(m: dict) -> tuple[str, str]:
    pm = m.get("phase_margin_deg")
    gm = m.get("gain_margin_db")
    pm_s = "n/a" if pm is None else f"{pm:.1f}"
    if gm is None and m.get("gain_margin_min_db") is not None:
        gm_s = f">= {m['gain_margin_min_db']:.1f}"
    else:
        gm_s = "n/a" if gm is None else f"{gm:.1f}"
    return pm_s, gm_s


def comparison_table(columns: dict, axes, params: dict) -> str:
    """Markdown: one column per scored set (label -> score_set()), params[label] its values."""
    labels = list(columns)
    lines = ["| | " + " | ".join(labels) + " |", "|---" * (len(labels) + 1) + "|"]
    for sc, key, text, fmt in ROWS:
        cells = []
        for lab in labels:
            m = columns[lab]["means"]
            v = None if m is None else m.get(sc, {}).get(key)
            cells.append("crashed" if m is None else ("n/a" if v is None else fmt.format(v)))
        lines.append(f"| {text} | " + " | ".join(cells) + " |")
    for axis in axes:
        cells = []
        for lab in labels:
            pm_s, gm_s = _margin_cells(columns[lab]["margins"].get(axis) or {})
            cells.append(f"{pm_s} deg / {gm_s} dB")
        lines.append(f"| {axis} PM / GM | " + " | ".join(cells) + " |")
    defaults = P.defaults()
    for name in SHOWN:
        cells = [f"{float(params[lab].get(name, defaults[name])):g}" for lab in labels]
        lines.append(f"| `{name}` | " + " | ".join(cells) + " |")
    # a failure names its set already when it comes from table1_runs ("label: S4: crashed")
    notes = [f if f.startswith(f"{lab}:") else f"{lab}: {f}"
             for lab in labels if (f := columns[lab]["failed"])]
    return "\n".join(lines) + ("\n\n" + "\n".join(f"- {n}" for n in notes) if notes else "")


def summary(col: dict) -> dict:
    """The --json view of one scored set: Table 1 means, margins, and why it failed."""
    return {"table1": col["means"], "margins": col["margins"], "failed": col["failed"]}
