"""The campaign's report folder: PNG plots and an index page.

For each scenario the first run's log gives the traces (attitude error, PWM,
yaw rate); all runs give the per-metric box plots. Everything is recomputed
from the logs and the results, so a report can be rebuilt from a campaign's
output folder alone.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from .att_scoring import command_at, target_at
from .table1 import ROWS, scenario_key


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _quat_to_roll_pitch(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
    return roll, pitch


def _save_trace(plt, out_dir: Path, fname: str, t, series, *, ylabel: str, title: str,
                span=None, span_label: str = "", legend_cols: int = 1) -> str:
    """One time-series figure: series = [(values, label or None), ...]."""
    fig, ax = plt.subplots(figsize=(8, 3))
    for values, label in series:
        ax.plot(t, values, lw=0.5, label=label)
    if span is not None:
        ax.axvspan(*span, color="tab:green", alpha=0.08, label=span_label)
    ax.set_xlabel("sim time [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc="upper right", ncol=legend_cols, fontsize=7)
    fig.tight_layout()
    fig.savefig(out_dir / fname, dpi=110)
    plt.close(fig)
    return fname


def trace_plots(log, name: str, out_dir: Path, windows) -> list[str]:
    """Attitude error, PWM and yaw-rate traces of one run; returns file names."""
    plt = _plt()
    files = []
    ch = log.channels
    st = ch.get("/fc/status")
    gt = ch.get("/gt_att")
    if st is not None and gt is not None and len(st) and len(gt):
        idx = np.clip(np.searchsorted(gt["sim_ns"], st["sim_ns"]), 0, len(gt) - 1)
        roll, pitch = _quat_to_roll_pitch(gt["q_wxyz"][idx])
        series = []
        for label, ref in (("vs command", command_at(log, st["sim_ns"], st)),
                           ("vs FC target", target_at(log, st["sim_ns"], st))):
            if ref is not None:
                series.append((np.degrees(np.hypot(roll - ref[:, 0], pitch - ref[:, 1])), label))
        files.append(_save_trace(
            plt, out_dir, f"{name}_attitude_error.png", st["sim_ns"] / 1e9, series,
            ylabel="attitude error [deg]", span=windows[2], span_label="analysis window",
            title=f"{name}: roll/pitch error vs the command and the FC's own target, run 0"))
    pwm = ch.get("/pwm")
    if pwm is not None and len(pwm):
        us = pwm["pwm_us"]
        files.append(_save_trace(
            plt, out_dir, f"{name}_pwm.png", pwm["sim_ns"] / 1e9,
            [(us[:, m], f"motor {m + 1}") for m in range(4)], ylabel="PWM [us]",
            title=f"{name}: motor PWM, run 0", legend_cols=4))
    if gt is not None and len(gt):
        files.append(_save_trace(
            plt, out_dir, f"{name}_yaw_rate.png", gt["sim_ns"] / 1e9,
            [(gt["rates_frd_rad_s"][:, 2], None)], ylabel="yaw rate [rad/s]",
            span=windows[3], span_label="yaw window",
            title=f"{name}: true body yaw rate, run 0"))
    return files


def box_plots(results, out_dir: Path) -> list[str]:
    plt = _plt()
    files = []
    names = sorted({scenario_key(r.spec.scenario) for r in results})
    for key, label, unit, _fmt in ROWS:
        data = []
        for n in names:
            vals = [r.metrics.get(key) for r in results if scenario_key(r.spec.scenario) == n]
            data.append([v for v in vals if v is not None and np.isfinite(v)])
        if not any(data):
            continue
        fig, ax = plt.subplots(figsize=(6, 3))
        ax.boxplot(data, tick_labels=names)
        ax.set_ylabel(f"{label} [{unit}]")
        ax.set_title(f"{label} per scenario ({len(results) // max(len(names), 1)} runs each)")
        fig.tight_layout()
        files.append(f"box_{key}.png")
        fig.savefig(out_dir / files[-1], dpi=110)
        plt.close(fig)
    return files


def write_report(results, table_md: str, table_json: dict, out_dir: Path, *,
                 extra_sections: list[tuple[str, str]] = ()) -> Path:
    """Plots + index.html in out_dir/report; returns the index path."""
    from .mcap_log import read_log

    rep = out_dir / "report"
    rep.mkdir(parents=True, exist_ok=True)
    images = []
    seen = set()
    for r in results:
        name = scenario_key(r.spec.scenario)
        if name in seen or not Path(r.spec.log_path).exists():   # --keep-logs none
            continue
        seen.add(name)
        log = read_log(r.spec.log_path)
        images += trace_plots(log, name, rep, r.spec.windows)
    images += box_plots(results, rep)
    (rep / "table1.md").write_text(table_md + "\n")
    (rep / "table1.json").write_text(json.dumps(table_json, indent=2) + "\n")
    parts = ["<!doctype html><meta charset='utf-8'><title>silbridge benchmark</title>",
             "<h1>silbridge benchmark</h1>", "<h2>Table 1</h2>",
             f"<pre>{html.escape(table_md)}</pre>"]
    for title, body in extra_sections:
        parts.append(f"<h2>{html.escape(title)}</h2><pre>{html.escape(body)}</pre>")
    parts.append("<h2>Plots</h2>")
    for img in images:
        parts.append(f"<figure><img src='{img}'><figcaption>{img}</figcaption></figure>")
    index = rep / "index.html"
    index.write_text("\n".join(parts) + "\n")
    return index
