"""The nav suite's report page (OUT/nav-report.md): the command, the table, the
definitions of the metrics, and per plan a top view of the first kept run of each
controller over the plan's path. Everything on it is recomputed from the logs and the
results, as the paper suite's report is.
"""

from __future__ import annotations

from pathlib import Path

from silbridge.tools.benchmark.nav.campaign import FC_LABELS, load_track
from silbridge.tools.benchmark.nav.plans import PLANS
from silbridge.tools.benchmark.nav.scoring import ARRIVE_M, JERK_BIN_S, PASS_M, TRACK_SETTLE_S
from silbridge.tools.benchmark.nav.spline import reference_path

DEFINITIONS = f"""\
All metrics come from the bridge's ground truth (/gt_nav, /gt_att of the run log), never
from an autopilot's telemetry.
- N1: overshoot = how far past each target the vehicle went along its leg's direction (worst
  leg); time to arrive = command to the first true position within {ARRIVE_M:g} m (mean of
  the legs); peak speed = largest true horizontal speed.
- N2: from {TRACK_SETTLE_S:g} s after each velocity command to the next one: RMS of the
  horizontal velocity error and of the heading error (wrapped to +-180 deg); the worst
  heading error at a leg's end.
- N3/N4: from AUTO to the first true position within {ARRIVE_M:g} m of the last waypoint
  (once the vehicle has passed within {PASS_M:g} m of the one before it): the time; the horizontal distance to the reference path
  (straight legs, and spline legs shaped as ArduCopter 4.6 shapes them) as RMS and maximum;
  the peak horizontal acceleration and the RMS horizontal jerk of the true velocity averaged
  over {JERK_BIN_S * 1000:g} ms bins.
"""


def _top_view(plan_name: str, results, out_dir: Path) -> str | None:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    plan = PLANS[plan_name]
    fig, ax = plt.subplots(figsize=(5, 5))
    if plan.kind == "mission":
        path, _ = reference_path((0.0, 0.0), plan.steps)
        ax.plot(path[:, 1], path[:, 0], "k--", lw=0.8, label="reference path")
    elif plan.kind == "goto":
        pts = [(0.0, 0.0)] + [(g.north_m, g.east_m) for g in plan.steps]
        ax.plot([p[1] for p in pts], [p[0] for p in pts], "k--", lw=0.8, label="legs")
    drawn = False
    for fc in FC_LABELS:
        r = next((r for r in results if r.plan == plan_name and r.fc == fc and r.log
                  and r.status == "ok"), None)
        if r is None:
            continue
        tr = load_track(r.log)
        ax.plot(tr.pos_ne[:, 1], tr.pos_ne[:, 0], lw=0.8, label=f"{FC_LABELS[fc]} seed {r.seed}")
        drawn = True
    if not drawn:
        plt.close(fig)
        return None
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.legend(fontsize=7)
    ax.set_title(f"{plan_name}: {plan.title}", fontsize=9)
    name = f"nav-{plan_name}.png"
    fig.savefig(out_dir / name, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return name


def write_nav_report(results, table_md: str, out_dir: Path, command: str) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    parts = ["# Navigation benchmark", "", f"`{command}`", "",
             "Each cell: mean / median over the runs that flew the plan.", "", table_md, "",
             "## Definitions", "", DEFINITIONS, "## Runs", "",
             "| plan | FC | seed | status | sim s at the end | wall s | reason |",
             "|---|---|---|---|---|---|---|"]
    for r in results:
        parts.append(f"| {r.plan} | {FC_LABELS[r.fc]} | {r.seed} | {r.status} | "
                     f"{r.sim_s:.0f} | {r.wall_s:.0f} | {r.reason.replace('|', '/')} |")
    for name in dict.fromkeys(r.plan for r in results):
        png = _top_view(name, results, out_dir)
        if png:
            parts += ["", f"## {name}", "", f"![{name} top view]({png})"]
    page = out_dir / "nav-report.md"
    page.write_text("\n".join(parts) + "\n")
    return page
