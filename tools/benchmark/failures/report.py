"""The failures suite's results page (OUT/failures-report.md), written by the command from
the runs: the command line, the table, the translation table and the equalised failsafe
settings, the definitions, every run with what the autopilot said after the fault, and
per plan a side view (height over time) of the first kept run of each autopilot."""

from __future__ import annotations

from pathlib import Path

from silbridge.tools.benchmark.failures import failsafe_params, scoring
from silbridge.tools.benchmark.failures.plans import ALT_M, PHASE_AT_S, PLANS
from silbridge.tools.benchmark.failures.translate import table_markdown
from silbridge.tools.benchmark.table1_compare import FC_LABELS

DEFINITIONS = f"""\
Every plan takes off to {ALT_M:g} m, holds, starts its phase at {PHASE_AT_S:g} s of sim time
(hold: the hover goes on; mission: AUTO round an 80 m square) and meets its fault at the
same sim time for every autopilot. Numbers come from the bridge's ground truth; the
autopilot's MAVLink says only what it detected and did.
- detection: seconds from the fault to the first STATUSTEXT of severity WARNING or worse, or
  the first failsafe mode change, up to {scoring.DETECT_GRACE_S:g} s after the fault ends;
- action: the first mode change in that window (or a disarm in the air); none;
- outcome: crashed (ground met faster than {scoring.CRASH_M_S:g} m/s, or tilted past
  {scoring.UPSET_DEG:g} deg at the end), landed upright, or still flying at the end;
- worst horizontal deviation: hold: from the true position where the fault hit, over the
  whole fault; mission: from the mission's path, until the autopilot acted;
- worst vertical deviation: from the height where the fault hit (mission: {ALT_M:g} m),
  until the autopilot acted (a LAND descends on purpose);
- landing distance: from home after an RTL, else from the point where the fault hit.
"""


def _side_view(name: str, results, out_dir: Path) -> str | None:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    fig, ax = plt.subplots(figsize=(6, 3))
    drawn = False
    for fc in FC_LABELS:
        r = next((r for r in results if r.plan == name and r.fc == fc and r.log
                  and r.status == "ok"), None)
        if r is None:
            continue
        tr = scoring.load_truth(r.log)
        step = max(1, len(tr.t_s) // 4000)
        ax.plot(tr.t_s[::step], tr.alt[::step], lw=0.8, label=f"{FC_LABELS[fc]} seed {r.seed}")
        drawn = True
    if not drawn:
        plt.close(fig)
        return None
    plan = PLANS[name]
    ax.axvspan(plan.fault_on_s, plan.fault_off_s, color="red", alpha=0.1, label="fault")
    ax.set_xlabel("sim time [s]")
    ax.set_ylabel("height above home [m]")
    ax.legend(fontsize=7)
    ax.set_title(f"{name}: {plan.title}", fontsize=8)
    png = f"failures-{name}.png"
    fig.savefig(out_dir / png, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return png


def write_failures_report(results, table_md: str, out_dir: Path, command) -> Path:
    """command: the command line, or the lines of a campaign flown in parts (merge.py)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    how = [f"`{command}`"] if isinstance(command, str) else (
        ["Flown in parts, joined by `python -m silbridge.tools.benchmark.failures.merge` (a "
         "later part's run of a seed replaces an earlier one):", ""]
        + [f"- `{c}`" for c in command])
    parts = ["# Failure benchmark: results", "", *how, "",
             "Written by the command from its runs; cells are medians over the runs "
             "measured, words are counts.", "", table_md, "", "## Definitions", "",
             DEFINITIONS, "## How each fault reaches each autopilot", "", table_markdown(), "",
             "## Failsafe settings, equal for all three", "", failsafe_params.describe(), "",
             "## Runs", "",
             "| plan | autopilot | seed | status | sim s | wall s | said after the fault "
             "| reason |",
             "|---|---|---|---|---|---|---|---|"]
    for r in results:
        said = " / ".join(t for _, _, t in r.texts[:4]).replace("|", "/")
        parts.append(f"| {r.plan} | {FC_LABELS[r.fc]} | {r.seed} | {r.status} | {r.sim_s:.0f} "
                     f"| {r.wall_s:.0f} | {said} | {r.reason.replace('|', '/')} |")
    for name in dict.fromkeys(r.plan for r in results):
        png = _side_view(name, results, out_dir)
        if png:
            parts += ["", f"## {name}", "", f"![{name} height]({png})"]
    page = out_dir / "failures-report.md"
    page.write_text("\n".join(parts) + "\n")
    return page
