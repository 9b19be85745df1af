"""The benchmark report page (report/index.html): Table 1, plots, configuration, logs.

Plain HTML with its style inline (no script, nothing fetched), so the page
opens from the campaign's folder in any browser and survives being copied:
- Table 1 as an HTML table: one column group per scenario, each controller
  that ran (ours, ArduCopter) side by side with the paper's figure (Kim et
  al., Table 1) beside them; mean ± std, n in each cell's tooltip;
- the plots, each in a figure with a caption saying what it shows;
- the run's configuration: campaign settings, the physics/sensor rates the
  logs recorded, parameter overrides, the scenarios flown;
- every run with its seed, wall time, integrity verdict and a link to its
  MCAP log (relative, so the folder can move) when the log was kept.
tools/benchmark/report.py makes the plots and calls render_index().
"""

from __future__ import annotations

import datetime
import html
import os
from pathlib import Path

from silbridge.tools.benchmark.table1 import PAPER, ROWS, _cell, scenario_key
from silbridge.tools.benchmark.table1_compare import comparison_markdown

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;
max-width:1200px;padding:0 1em;color:#222;line-height:1.4}
h1{margin-bottom:.2em}.sub{color:#555;margin-top:0}
table{border-collapse:collapse;margin:1em 0;font-size:14px}
th,td{border:1px solid #ccc;padding:4px 8px;text-align:right;white-space:nowrap}
th{background:#f2f4f7}td.l,th.l{text-align:left}
th.group{text-align:center;background:#e4e9f0}td.paper,th.paper{background:#fbf7e9}
tr:nth-child(even) td{background-color:#fafafa}tr:nth-child(even) td.paper{background:#f6f0d8}
td.bad{color:#b00020;font-weight:600}td.ok{color:#1b7f3b}
.figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:8px 20px}
figure{margin:0 0 1em 0}figure img{width:100%;border:1px solid #ddd}
figcaption{font-size:13px;color:#444}
dl.cfg{display:grid;grid-template-columns:max-content auto;gap:2px 16px}
dl.cfg dt{font-weight:600}dl.cfg dd{margin:0}
code{background:#f2f2f2;padding:0 3px}
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _controllers(table: dict) -> tuple[list[str], list[str]]:
    """(scenarios in table order, controllers in order): 'S1 ArduCopter' is S1's ArduCopter."""
    scenarios, fcs = [], []
    for key in table["scenarios"]:
        sc, _, fc = key.partition(" ")
        fc = fc or "ours"
        if sc not in scenarios:
            scenarios.append(sc)
        if fc not in fcs:
            fcs.append(fc)
    return scenarios, fcs


def table1_html(table: dict) -> str:
    """Table 1: metrics as rows; per scenario the controllers side by side, then the paper."""
    scenarios, fcs = _controllers(table)
    cols = []                                       # (scenario, table key or None for paper)
    for sc in scenarios:
        for fc in fcs:
            key = sc if fc == "ours" else f"{sc} {fc}"
            if key in table["scenarios"]:
                cols.append((sc, key, fc))
        if sc in PAPER:
            cols.append((sc, None, "paper"))
    head1 = ['<th class="l" rowspan="2">metric</th>']
    for sc in scenarios:
        span = sum(1 for c in cols if c[0] == sc)
        head1.append(f'<th class="group" colspan="{span}">{_e(sc)}</th>')
    head2 = [f'<th class="{"paper" if fc == "paper" else ""}">{_e(fc)}</th>'
             for _sc, _key, fc in cols]
    rows = []
    for key, label, unit, fmt in ROWS:
        cells = [f'<td class="l">{_e(label)} ({_e(unit)})</td>']
        for sc, tkey, fc in cols:
            if tkey is None:
                v = PAPER[sc].get(key)
                cells.append(f'<td class="paper">{"" if v is None else _e(v)}</td>')
                continue
            stat = table["scenarios"][tkey].get(key)
            n = stat.get("n") if stat else 0
            cells.append(f'<td title="n = {n}">{_e(_cell(stat, fmt))}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return ('<table class="table1"><thead><tr>' + "".join(head1) + "</tr><tr>"
            + "".join(head2) + "</tr></thead><tbody>" + "\n".join(rows) + "</tbody></table>")


def config_html(table: dict, results, log_meta: dict | None) -> str:
    items = [("runs per scenario", table.get("runs")),
             ("sim time per run", f'{table["duration_s"]:g} s' if "duration_s" in table else None),
             ("flight controllers", ", ".join(table.get("fc", [])) or None),
             ("executor", table.get("executor")),
             ("seeds", _seeds(results)),
             ("parameter overrides", ", ".join(f"{k}={v:g}" for k, v in
                                                (table.get("params") or {}).items()) or "none"),
             ("simulated in total", f'{table["sim_s_total"]:.0f} s'
              if "sim_s_total" in table else None),
             ("wall time", f'{table["wall_s"]:.1f} s' if "wall_s" in table else None)]
    if log_meta:
        cfg = log_meta.get("config", {})
        rates = ", ".join(f"{k.removesuffix('_hz')} {cfg[k]:g} Hz" for k in
                          ("physics_hz", "imu_hz", "pwm_hz", "baro_hz", "mag_hz", "gnss_hz")
                          if isinstance(cfg.get(k), (int, float)))
        items += [("rates (from the first log)", rates or None),
                  ("mode", cfg.get("mode")), ("transport", cfg.get("transport")),
                  ("silbridge", (log_meta.get("software") or {}).get("silbridge"))]
    if results:
        w = results[0].spec.windows
        items.append(("metric windows", f"warm-up {w[0][0]:g}-{w[0][1]:g} s, transient "
                      f"{w[1][0]:g}-{w[1][1]:g} s, analysis {w[2][0]:g}-{w[2][1]:g} s, "
                      f"yaw {w[3][0]:g}-{w[3][1]:g} s"))
    body = "".join(f"<dt>{_e(k)}</dt><dd>{_e(v)}</dd>" for k, v in items if v is not None)
    return f'<dl class="cfg">{body}</dl>'


def _seeds(results) -> str | None:
    seeds = sorted({r.spec.seed for r in results})
    if not seeds:
        return None
    return f"{seeds[0]}..{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])


def runs_html(results, rep_dir: Path) -> str:
    head = ("<tr><th class='l'>scenario</th><th class='l'>FC</th><th>run</th><th>seed</th>"
            "<th>wall [s]</th><th>att RMS [deg]</th><th class='l'>integrity</th>"
            "<th class='l'>log</th></tr>")
    rows = []
    for r in sorted(results, key=lambda r: (scenario_key(r.spec.scenario), r.spec.fc,
                                            r.spec.run_index)):
        s = r.spec
        log = Path(s.log_path)
        if log.exists():
            rel = os.path.relpath(log, rep_dir).replace(os.sep, "/")
            link = f'<a href="{_e(rel)}">{_e(log.name)}</a>'
        else:
            link = "not kept"
        ok = not r.problems
        verdict = "ok" if ok else f"FAILED: {r.problems[0]}"
        rms = r.metrics.get("att_rms_deg")
        rows.append(f"<tr><td class='l'>{_e(scenario_key(s.scenario))}</td>"
                    f"<td class='l'>{_e(s.fc)}</td><td>{s.run_index}</td><td>{s.seed}</td>"
                    f"<td>{r.wall_s:.1f}</td>"
                    f"<td>{'n/a' if rms is None else f'{rms:.3f}'}</td>"
                    f"<td class='l {'ok' if ok else 'bad'}'>{_e(verdict)}</td>"
                    f"<td class='l'>{link}</td></tr>")
    return f'<table class="runs"><thead>{head}</thead><tbody>{"".join(rows)}</tbody></table>'


# What the vibration section shows (tools/benchmark/report_spectrum.py makes its figures).
_VIBRATION_NOTE = (
    "<p class='sub'>Spectra of the IMU as the FC read it (and of the chip's raw samples when "
    "the log has them), first run of each scenario: Welch's average over the analysis window "
    "and a spectrogram of the whole run. Dashed: the rotor harmonics 1x (imbalance), 2x "
    "(blade pass of a two-blade prop) and 3x, from the logged rotor speed. "
    "<code>silbridge analyze LOG --spectrum</code> lists the peaks.</p>")


def _figures(figures) -> list[str]:
    return [f"<figure><img src='{_e(img)}' alt='{_e(caption)}'>"
            f"<figcaption>{_e(caption)}</figcaption></figure>" for img, caption in figures]


def render_index(*, table: dict, results, figures: list[tuple[str, str]], rep_dir: Path,
                 log_meta: dict | None = None, scenarios: dict | None = None,
                 extra_sections=(), spectra=()) -> str:
    """The whole page. figures, spectra: (image file in rep_dir, caption); scenarios:
    name -> description of the scenarios flown."""
    n = max((st.get("n", 0) for sc in table["scenarios"].values() for st in sc.values()
             if isinstance(st, dict)), default=0)
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    parts = [
        "<!doctype html>", "<html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        "<title>silbridge benchmark report</title>", f"<style>{_CSS}</style></head><body>",
        "<h1>silbridge benchmark</h1>",
        f"<p class='sub'>Generated {when}. Table 1 of Kim et al. reproduced: mean ± std over "
        f"n = {n} runs per scenario and controller (hover a cell for its n); the paper's "
        "figures (AirSim, their SIL FC) in the shaded columns. Files: "
        "<a href='table1.md'>table1.md</a>, <a href='table1.json'>table1.json</a>.</p>",
        "<h2 id='table1'>Table 1</h2>", table1_html(table),
        "<p class='sub'>p-p: PWM peak to peak; sat: time any motor saturates; RMS/P95: "
        "attitude error; noise rows: RMS over 20-200 Hz of the filtered gyro, the IMU input, "
        "the D terms and the motor PWM; cp/cr/cy: mixer offsets. n/a: the controller does "
        "not report it.</p>",
    ]
    if table.get("comparison"):     # what the page may claim: the paired verdicts, not means
        parts += ["<h2 id='paired'>Controllers compared, paired by seed</h2>",
                  f"<pre>{_e(comparison_markdown(table['comparison']))}</pre>"]
    if scenarios:
        parts.append("<h2 id='scenarios'>Scenarios</h2><table class='scen'><tbody>"
                     + "".join(f"<tr><td class='l'><b>{_e(k)}</b></td><td class='l'>{_e(v)}"
                               "</td></tr>" for k, v in scenarios.items())
                     + "</tbody></table>")
    parts.append("<h2 id='plots'>Plots</h2><div class='figs'>")
    parts += [*_figures(figures), "</div>"]
    if not figures:
        parts.append("<p>No plots (no logs kept and no finite metrics).</p>")
    if spectra:
        parts += ["<h2 id='vibration'>Vibration</h2>", _VIBRATION_NOTE, "<div class='figs'>",
                  *_figures(spectra), "</div>"]
    for title, body in extra_sections:
        parts.append(f"<h2>{_e(title)}</h2><pre>{_e(body)}</pre>")
    parts += ["<h2 id='config'>Configuration</h2>", config_html(table, results, log_meta),
              "<h2 id='runs'>Runs and logs</h2>",
              "<p class='sub'>Open a log in Foxglove with the layout in the repository "
              "(<code>docs/foxglove_layout.json</code>); <code>silbridge analyze LOG</code> "
              "recomputes its metrics.</p>", runs_html(results, rep_dir), "</body></html>"]
    return "\n".join(parts) + "\n"
