"""The campaign's report folder: PNG plots and an index page.

For each scenario (and controller) the first run's log gives the traces
(attitude error, PWM, yaw rate); all runs give the per-metric box plots. Each
plot comes with its caption; the page itself is tools/benchmark/report_html.py.
Everything is recomputed from the logs and the results, so a report can be
rebuilt from a campaign's output folder alone.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from silbridge.tools.benchmark.att_scoring import command_at, target_at
from silbridge.tools.benchmark.report_html import render_index
from silbridge.tools.benchmark.report_spectrum import spectrum_plots
from silbridge.tools.benchmark.table1 import ROWS, scenario_key
from silbridge.tools.logs.viz_frames import euler_from_quat


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


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


def trace_plots(log, name: str, out_dir: Path, windows, who: str = "run 0"
                ) -> list[tuple[str, str]]:
    """Attitude error, PWM and yaw-rate traces of one run: [(file name, caption)]."""
    plt = _plt()
    files = []
    ch = log.channels
    st = ch.get("/fc/status")
    gt = ch.get("/gt_att")
    if st is not None and gt is not None and len(st) and len(gt):
        idx = np.clip(np.searchsorted(gt["sim_ns"], st["sim_ns"]), 0, len(gt) - 1)
        euler = euler_from_quat(gt["q_wxyz"][idx])
        roll, pitch = euler[:, 0], euler[:, 1]
        series = []
        for label, ref in (("vs command", command_at(log, st["sim_ns"], st)),
                           ("vs FC target", target_at(log, st["sim_ns"], st))):
            if ref is not None:
                series.append((np.degrees(np.hypot(roll - ref[:, 0], pitch - ref[:, 1])), label))
        files.append((_save_trace(
            plt, out_dir, f"{_stem(name)}_attitude_error.png", st["sim_ns"] / 1e9, series,
            ylabel="attitude error [deg]", span=windows[2], span_label="analysis window",
            title=f"{name}: roll/pitch error vs the command and the FC's own target, {who}"),
            f"{name}, {who}: combined roll/pitch error of the true attitude against the "
            "scenario's command and against the FC's own shaped target at each PWM tick; "
            "shaded: the analysis window of the RMS and P95 figures."))
    pwm = ch.get("/pwm")
    if pwm is not None and len(pwm):
        us = pwm["pwm_us"]
        files.append((_save_trace(
            plt, out_dir, f"{_stem(name)}_pwm.png", pwm["sim_ns"] / 1e9,
            [(us[:, m], f"motor {m + 1}") for m in range(4)], ylabel="PWM [us]",
            title=f"{name}: motor PWM, {who}", legend_cols=4),
            f"{name}, {who}: the PWM of the four motors as the FC published it "
            "(ArduCopter motor order); its spread over the analysis window is p-p."))
    if gt is not None and len(gt):
        files.append((_save_trace(
            plt, out_dir, f"{_stem(name)}_yaw_rate.png", gt["sim_ns"] / 1e9,
            [(gt["rates_frd_rad_s"][:, 2], None)], ylabel="yaw rate [rad/s]",
            span=windows[3], span_label="yaw window",
            title=f"{name}: true body yaw rate, {who}"),
            f"{name}, {who}: the true body yaw rate (ground truth); shaded: the yaw "
            "window of the yaw-rate figure."))
    return files


def _stem(name: str) -> str:
    return name.replace(" ", "_")


def box_plots(results, out_dir: Path) -> list[tuple[str, str]]:
    plt = _plt()
    files = []
    def group(r) -> str:    # one box per scenario and controller
        fc = getattr(r.spec, "fc", "ours")
        return scenario_key(r.spec.scenario) + ("" if fc == "ours" else f" {fc}")
    names = sorted({group(r) for r in results})
    for key, label, unit, _fmt in ROWS:
        data = []
        for n in names:
            vals = [r.metrics.get(key) for r in results if group(r) == n]
            data.append([v for v in vals if v is not None and np.isfinite(v)])
        if not any(data):
            continue
        fig, ax = plt.subplots(figsize=(6, 3))
        ax.boxplot(data, tick_labels=names)
        ax.set_ylabel(f"{label} [{unit}]")
        ax.set_title(f"{label} per scenario ({len(results) // max(len(names), 1)} runs each)")
        fig.tight_layout()
        files.append((f"box_{key}.png",
                       f"{label} [{unit}] of every run, per scenario and controller (box: "
                       "quartiles and median; whiskers: 1.5 interquartile ranges; circles: "
                       "outliers)."))
        fig.savefig(out_dir / files[-1][0], dpi=110)
        plt.close(fig)
    return files


def write_report(results, table_md: str, table_json: dict, out_dir: Path, *,
                 extra_sections: list[tuple[str, str]] = ()) -> Path:
    """Plots + index.html in out_dir/report; returns the index path."""
    from silbridge.tools.logs.mcap_log import read_log

    rep = out_dir / "report"
    rep.mkdir(parents=True, exist_ok=True)
    figures, spectra = [], []
    seen = set()
    first_meta = None
    described = {}
    for r in results:
        name = scenario_key(r.spec.scenario)
        fc = getattr(r.spec, "fc", "ours")
        if (name, fc) in seen or not Path(r.spec.log_path).exists():   # --keep-logs none
            continue
        seen.add((name, fc))
        log = read_log(r.spec.log_path)
        first_meta = first_meta or log.metadata
        sc = log.metadata.get("scenario") or {}
        described.setdefault(name, sc.get("description", ""))
        label = name if fc == "ours" else f"{name} {fc}"
        figures += trace_plots(log, label, rep, r.spec.windows,
                               who=f"run {r.spec.run_index} (seed {r.spec.seed})")
        spectra += spectrum_plots(_plt(), log, label, rep, r.spec.windows[2],
                                  who=f"run {r.spec.run_index} (seed {r.spec.seed})")
    figures += box_plots(results, rep)
    (rep / "table1.md").write_text(table_md + "\n")
    (rep / "table1.json").write_text(json.dumps(table_json, indent=2) + "\n")
    index = rep / "index.html"
    index.write_text(render_index(table=table_json, results=results, figures=figures,
                                  rep_dir=rep, log_meta=first_meta, scenarios=described,
                                  extra_sections=extra_sections, spectra=spectra))
    return index
