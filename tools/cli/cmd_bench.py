"""`silbridge bench`: the paper's campaign (Table 1) over local processes or Ray."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from silbridge.tools.benchmark.campaign import CampaignError, make_specs, run_campaign
from silbridge.tools.cli.flight_args import parse_params
from silbridge.tools.benchmark.report import write_report
from silbridge.tools.benchmark.table1 import SCORING_ROWS, aggregate, markdown, scenario_key

HELP = "run the paper's benchmark campaign (S1..S4, N runs) and print Table 1"


def add_campaign_arguments(p) -> None:
    p.add_argument("--scenarios", default="S1,S2,S3,S4",
                   help="comma-separated scenario names or TOML files (default S1,S2,S3,S4)")
    p.add_argument("--runs", type=int, default=20, help="runs per scenario (default 20)")
    p.add_argument("--duration", type=float, default=120.0, metavar="S",
                   help="simulated seconds per run (default 120)")
    p.add_argument("--seed", type=int, default=1, help="seed of run 0; run i uses seed + i")
    p.add_argument("--jobs", type=int, default=None,
                   help="parallel runs (default: CPU count)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local process pool (default) or a Ray cluster")
    p.add_argument("--ray-address", default=None,
                   help="Ray cluster address for --executor ray (default: start a local Ray)")
    p.add_argument("--imu-hz", type=float, default=None, help="IMU rate (default 1000)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="FC parameter for every run, e.g. ATC_RAT_RLL_D=0.004 (repeatable)")
    p.add_argument("--warmup", type=float, nargs=2, default=(0.0, 10.0), metavar=("A", "B"))
    p.add_argument("--transient", type=float, nargs=2, default=(10.0, 30.0), metavar=("A", "B"))
    p.add_argument("--analysis", type=float, nargs=2, default=(30.0, 120.0), metavar=("A", "B"))
    p.add_argument("--yaw-window", type=float, nargs=2, default=(90.0, 120.0),
                   metavar=("A", "B"))
    p.add_argument("--out", default="bench-out", help="output folder (default bench-out)")
    p.add_argument("--keep-logs", choices=("all", "first", "none"), default="first",
                   help="MCAP logs to keep (~45 MB per 120 s run): all, first run of each "
                        "scenario (default; the report's traces use it), none")
    p.add_argument("--no-report", action="store_true", help="skip the plots and index page")
    p.add_argument("--viz-hz", type=float, default=0.0, metavar="N",
                   help="viewable /viz channels in our FC's logs at N Hz (default 0: off in "
                        "campaigns, their cost; `fly --log` has them at 1000)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_arguments(p) -> None:
    add_campaign_arguments(p)
    p.add_argument("--fc", default="ours", metavar="ours|ardupilot|px4|ours,ardupilot,px4",
                   help="flight controller(s): our SIL FC (default), ArduCopter SITL over its "
                        "JSON interface, PX4 SITL over MAVLink HIL, or several side by side in "
                        "one Table 1")
    p.add_argument("--sitl", default=None, metavar="PATH",
                   help="--fc ardupilot: the arducopter binary (default: $SILBRIDGE_ARDUCOPTER, "
                        "then `arducopter` on PATH)")
    p.add_argument("--sitl-speedup", type=float, default=50.0, metavar="X",
                   help="--fc ardupilot: SITL --speedup (lockstep either way; higher only lets "
                        "SITL run ahead of the wall clock, default 50)")
    p.add_argument("--px4", default=None, metavar="PATH",
                   help="--fc px4: the px4 SITL binary, etc/ beside its bin/ (default: "
                        "$SILBRIDGE_PX4, then `px4` on PATH)")


FC_LABELS = {"ardupilot": "ArduCopter", "px4": "PX4"}


def _group_name(r) -> str:
    """Table 1 column group: the scenario for our FC, 'S1 ArduCopter' for ArduCopter runs."""
    name = scenario_key(r.spec.scenario)
    return f"{name} {FC_LABELS[r.spec.fc]}" if r.spec.fc in FC_LABELS else name


def fc_choice(text: str) -> list[str]:
    fcs = [f.strip().lower() for f in text.split(",") if f.strip()]
    bad = [f for f in fcs if f not in ("ours", "ardupilot", "px4")]
    if not fcs or bad:
        raise CampaignError(f"--fc wants ours, ardupilot, px4 or a list such as "
                            f"ours,ardupilot,px4, not {text!r}")
    return list(dict.fromkeys(fcs))


def campaign_inputs(args):
    if args.runs < 1:
        raise CampaignError("--runs must be >= 1")
    if args.duration <= 0:
        raise CampaignError("--duration must be > 0")
    scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    if not scenarios:
        raise CampaignError("--scenarios is empty: name at least one, e.g. S1")
    windows = (tuple(args.warmup), tuple(args.transient), tuple(args.analysis),
               tuple(args.yaw_window))
    params = tuple(sorted(parse_params(args.param).items()))
    return scenarios, windows, params


def run(args) -> int:
    scenarios, windows, params = campaign_inputs(args)
    fcs = fc_choice(args.fc)
    sitl = None
    if "ardupilot" in fcs:
        from silbridge.tools.autopilots.sitl_ardupilot import HOW_TO_GET, find_arducopter
        sitl = find_arducopter(args.sitl)
        if sitl is None:
            fcs.remove("ardupilot")
            note = f"bench --fc ardupilot skipped: {HOW_TO_GET}"
            print(note, file=sys.stderr)
            if not fcs:
                if args.json:
                    print(json.dumps({"skipped": True, "fc": "ardupilot", "reason": note}))
                return 0
    px4 = None
    if "px4" in fcs:
        from silbridge.tools.autopilots.sitl_px4 import HOW_TO_GET as PX4_HOW_TO_GET
        from silbridge.tools.autopilots.sitl_px4 import find_px4
        found = find_px4(args.px4)
        px4 = found[0] if found else None
        if px4 is None:
            fcs.remove("px4")
            note = f"bench --fc px4 skipped: {PX4_HOW_TO_GET}"
            print(note, file=sys.stderr)
            if not fcs:
                if args.json:
                    print(json.dumps({"skipped": True, "fc": "px4", "reason": note}))
                return 0
    out_dir = Path(args.out)
    specs = []
    for fc in fcs:
        # ArduCopter's parameters are its own: our FC's --param overrides go to ours only.
        specs += make_specs(scenarios, args.runs, args.duration, out_dir, base_seed=args.seed,
                            imu_hz=args.imu_hz, params=params if fc == "ours" else (),
                            windows=windows, keep_logs=args.keep_logs, fc=fc, sitl=sitl,
                            sitl_speedup=args.sitl_speedup, viz_hz=args.viz_hz, px4=px4,
                            variant="full" if fc == "ours" else fc)
    t0 = time.monotonic()
    results = run_campaign(specs, jobs=args.jobs, executor=args.executor,
                           ray_address=args.ray_address)
    wall_s = time.monotonic() - t0
    # Ctrl-C / SIGTERM: the table covers the runs that finished; the partial ones are listed.
    from silbridge.tools.loop.stop_signals import STOP
    partial = [r for r in results
               if r.summary.get("interrupted") and not r.summary.get("skipped")]
    results = [r for r in results if not r.summary.get("interrupted")]
    if STOP.requested:
        stopped = {"interrupted": STOP.name, "runs_planned": len(specs),
                   "runs_done": len(results), "partial_logs": [r.spec.log_path for r in partial]}
        print(f"bench: INTERRUPTED by {STOP.name}: {len(results)} of {len(specs)} runs "
              f"finished; partial logs: {', '.join(stopped['partial_logs']) or 'none'}",
              file=sys.stderr)
        if not results:
            if args.json:
                print(json.dumps(stopped))
            return STOP.exit_code()
    table = aggregate(results, group=_group_name)
    if len(fcs) > 1:   # each scenario's ArduCopter column right after ours and the paper's
        sc = table["scenarios"]
        table["scenarios"] = {k: sc[k] for k in sorted(sc, key=lambda k: k.split(" ")[0])}
    table.update({"runs": args.runs, "duration_s": args.duration, "wall_s": wall_s, "fc": fcs,
                  "executor": args.executor, "params": dict(params),
                  "sim_s_total": sum(r.summary.get("sim_s", 0.0) for r in results)})
    if STOP.requested:
        table.update(stopped)
    md = markdown(table)
    scoring = markdown(table, paper=False, rows=SCORING_ROWS,
                       title="Attitude error scored both ways")
    for label in FC_LABELS.values():      # "S1 ArduCopter", "S1 PX4", not "... ours"
        md = md.replace(f" {label} ours |", f" {label} |")
        scoring = scoring.replace(f" {label} ours |", f" {label} |")
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "table1.md").write_text(md + "\n\n" + scoring + "\n")
    (out_dir / "table1.json").write_text(json.dumps(table, indent=2) + "\n")
    index = None
    if not args.no_report:
        index = write_report(results, md, table, out_dir,
                             extra_sections=[("Attitude error: command and FC target", scoring)])
    if args.json:
        print(json.dumps(table))
    else:
        print(md)
        print()
        print(scoring)
        print(f"\n{len(results)} runs, {table['sim_s_total']:.0f} s simulated in "
              f"{wall_s:.1f} s wall ({table['sim_s_total'] / max(wall_s, 1e-9):.0f}x real "
              f"time overall)")
        print(f"logs and tables in {out_dir}/" + (f", report {index}" if index else ""),
              file=sys.stdout)
    return STOP.exit_code(0)
