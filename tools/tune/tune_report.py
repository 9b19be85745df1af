"""The tuning report: Bode plots with coherence, step plots, and an index page
(index.html and report.md side by side, the same figures and tables).

Each frequency response is drawn over the sweep band; points with coherence
below the threshold the margins use are drawn faint, so a reader sees which
part of a curve the figures rest on.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from silbridge.tools.benchmark.report import _plt
from silbridge.tools.tune.tune_freq import Frf

# Response name -> (title, unit of |H|)
TITLES = {
    "plant": ("rate plant: mixer input -> true body rate", "rad/s per us"),
    "plant_gyro": ("rate plant seen by the FC: mixer input -> rate-loop gyro", "rad/s per us"),
    "open_loop": ("open loop at the plant input, L = -u_ctrl / u", ""),
    "sensitivity_in": ("input sensitivity 1 / (1 + L) = u / d", ""),
    "complementary_in": ("input complementary sensitivity L / (1 + L)", ""),
    "closed_loop": ("closed rate loop: rate target -> true rate", ""),
    "closed_loop_gyro": ("closed rate loop: rate target -> rate-loop gyro", ""),
    "sensitivity": ("rate sensitivity: rate target -> rate error", ""),
    "rate_loop": ("open rate loop: rate error -> rate-loop gyro", ""),
}


def bode_png(out_dir: Path, fname: str, frf: Frf, *, title: str, f_band, coh_min: float,
             model: Frf | None = None, margins: dict | None = None) -> str:
    plt = _plt()
    m = (frf.f_hz >= f_band[0]) & (frf.f_hz <= f_band[1]) & np.isfinite(frf.h)
    f, h, coh = frf.f_hz[m], frf.h[m], frf.coherence[m]
    good = coh >= coh_min
    mag = 20 * np.log10(np.abs(h))
    ph = np.degrees(np.unwrap(np.angle(h)))
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.4]})
    for ax, y, lab in ((axes[0], mag, "gain [dB]"), (axes[1], ph, "phase [deg]")):
        ax.semilogx(f, np.where(good, y, np.nan), lw=1.2, color="tab:blue", label="identified")
        ax.semilogx(f, y, lw=0.6, color="tab:blue", alpha=0.25)
        ax.set_ylabel(lab)
        ax.grid(True, which="both", alpha=0.3)
    if model is not None:
        mm = 20 * np.log10(np.abs(model.h))
        mp = np.degrees(np.unwrap(np.angle(model.h)))
        mp += 360.0 * np.round((ph[good][0] - mp[np.argmin(np.abs(model.f_hz - f[good][0]))]) / 360.0) \
            if good.any() else 0.0
        axes[0].semilogx(model.f_hz, mm, "--", color="tab:orange", lw=1, label="linearised model")
        axes[1].semilogx(model.f_hz, mp, "--", color="tab:orange", lw=1)
    if margins and margins.get("crossover_hz"):
        for ax in axes[:2]:
            ax.axvline(margins["crossover_hz"], color="tab:green", lw=0.8, alpha=0.6)
        axes[0].axhline(0.0, color="k", lw=0.5)
        axes[1].axhline(-180.0, color="k", lw=0.5)
    if margins and margins.get("phase_crossover_hz"):
        for ax in axes[:2]:
            ax.axvline(margins["phase_crossover_hz"], color="tab:red", lw=0.8, alpha=0.6)
    axes[2].semilogx(f, coh, color="tab:gray", lw=1)
    axes[2].axhline(coh_min, color="tab:red", lw=0.6, ls=":")
    axes[2].set_ylim(0, 1.05)
    axes[2].set_ylabel("coherence")
    axes[2].set_xlabel("frequency [Hz]")
    axes[0].legend(fontsize=7, loc="lower left")
    axes[0].set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out_dir / fname, dpi=100)
    plt.close(fig)
    return fname


def step_png(out_dir: Path, fname: str, t, target, actual, *, title: str, ylabel: str) -> str:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 3))
    ax.plot(t, target, lw=0.8, label="command")
    ax.plot(t, actual, lw=0.8, label="true")
    ax.set_xlabel("time from the step [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_dir / fname, dpi=100)
    plt.close(fig)
    return fname


def write_index(out_dir: Path, title: str, summary: dict, tables: list[tuple[str, str]],
                images: list[str]) -> Path:
    """index.html and report.md (same content) and summary.json in out_dir."""
    text_json = json.dumps(summary, indent=2, default=_jsonable)
    (out_dir / "summary.json").write_text(text_json + "\n")
    md = [f"# {title}", ""]
    parts = ["<!doctype html><meta charset='utf-8'>", f"<title>{html.escape(title)}</title>",
             f"<h1>{html.escape(title)}</h1>"]
    for head, body in tables:
        md += [f"## {head}", "", body, ""]
        parts.append(f"<h2>{html.escape(head)}</h2><pre>{html.escape(body)}</pre>")
    md += ["## Figures", ""]
    parts.append("<h2>Figures</h2>")
    for img in images:
        md.append(f"![{img}]({img})")
        parts.append(f"<figure><img src='{img}'><figcaption>{img}</figcaption></figure>")
    md += ["", "## Summary (JSON)", "", "```json", text_json, "```"]
    (out_dir / "report.md").write_text("\n".join(md) + "\n")
    index = out_dir / "index.html"
    index.write_text("\n".join(parts) + "\n")
    return index


def _jsonable(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    raise TypeError(f"not JSON serialisable: {type(v).__name__}")


def margins_table(summaries: dict) -> str:
    """Markdown: one row per axis with its margins and bandwidth."""
    cols = [("phase_margin_deg", "PM (deg)", "{:.1f}"), ("gain_margin_db", "GM (dB)", "{:.1f}"),
            ("crossover_hz", "crossover (Hz)", "{:.2f}"),
            ("phase_crossover_hz", "phase crossover (Hz)", "{:.2f}"),
            ("delay_margin_ms", "delay margin (ms)", "{:.1f}"),
            ("bandwidth_hz", "-3 dB bandwidth (Hz)", "{:.2f}")]
    lines = ["| axis | " + " | ".join(c[1] for c in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for axis, s in summaries.items():
        cells = []
        for key, _label, fmt in cols:
            v = s.get(key)
            if v is None and key == "gain_margin_db" and s.get("gain_margin_min_db") is not None:
                cells.append(">= " + fmt.format(s["gain_margin_min_db"]))
            else:
                cells.append("beyond the sweep" if v is None else fmt.format(v))
        lines.append(f"| {axis} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
