"""`silbridge bench`: the paper's campaign (Table 1) over local processes or Ray."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from silbridge.tools.benchmark.nav.command import SPEED as NAV_SPEED
from silbridge.tools.benchmark.campaign import (CampaignError, RunSpec, check_executor,
                                                make_specs, run_campaign)
from silbridge.tools.benchmark.report import write_report
from silbridge.tools.benchmark.run_params import run_params
from silbridge.tools.benchmark.table1 import SCORING_ROWS, aggregate, markdown, scenario_key
from silbridge.tools.benchmark.windows_fit import DEFAULTS as WINDOWS
from silbridge.tools.benchmark.windows_fit import FLAGS as WINDOW_FLAGS
from silbridge.tools.benchmark.windows_fit import PROTOCOL_S, fit_windows
from silbridge.tools.cli.aliases import add_deprecated_alias

HELP = "run the paper's benchmark campaign (S1..S4, N runs) and print Table 1"


def add_campaign_arguments(p) -> None:
    """The options `bench` and `ablate` share (ablate changes some defaults: its --help
    shows its own, as every "(default ...)" here is argparse's %(default)s)."""
    p.add_argument("--scenarios", default="S1,S2,S3,S4",
                   help="comma-separated scenario names or TOML files (default %(default)s)")
    p.add_argument("--runs", type=int, default=20, help="runs per scenario (default %(default)s)")
    p.add_argument("--duration", type=float, default=PROTOCOL_S, metavar="S",
                   help=f"simulated seconds per run (default %(default)g); shorter than the "
                        f"{PROTOCOL_S:g} s the default windows are made for: they are scaled "
                        f"to fit, and said so")
    p.add_argument("--seed", type=int, default=1,
                   help="seed of run 0; run i uses seed + i (default %(default)s)")
    p.add_argument("--jobs", type=int, default=None,
                   help="parallel runs: the local pool, or the CPUs of the Ray started here "
                        "(default: CPU count)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local process pool or a Ray cluster (default %(default)s)")
    p.add_argument("--ray-address", default=None,
                   help="Ray cluster address for --executor ray (default: start a local Ray)")
    p.add_argument("--imu-hz", type=float, default=None,
                   help="IMU rate (default: the scenario's)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="our FC's parameter for every run, e.g. ATC_RAT_RLL_D=0.004 "
                        "(repeatable; applied after --params)")
    p.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file of our FC's parameters for every run (read "
                        "only; checked before any run)")
    for name, flag in WINDOW_FLAGS.items():
        a, b = getattr(WINDOWS, name)
        # The default is the Windows tuple itself: argparse stores it as is when the flag
        # is not given (a given window is a new list), which is how campaign_inputs tells
        # a default window (scaled to a short run) from one the user asked for (never moved).
        p.add_argument(flag, type=float, nargs=2, default=getattr(WINDOWS, name),
                       metavar=("A", "B"),
                       help=f"{name} window in s of sim time (default {a:g} {b:g}, scaled "
                            f"to a shorter --duration); must lie inside the run")
    p.add_argument("--out", default="bench-out", help="output folder (default %(default)s)")
    p.add_argument("--keep-logs", choices=("all", "first", "none"), default="first",
                   help="MCAP logs to keep (~45 MB per 120 s run): all, first run of each "
                        "scenario (the report's traces use it), none (default %(default)s)")
    p.add_argument("--no-report", action="store_true",
                   help="skip the plots and the index page (report/)")
    p.add_argument("--viz-hz", type=float, default=0.0, metavar="N",
                   help="viewable /viz channels in our FC's logs at N Hz (default %(default)g: "
                        "off in campaigns, their cost; `fly --log` has them at every sample)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_arguments(p) -> None:
    p.add_argument("--suite", choices=("paper", "nav", "failures"), default="paper",
                   help="paper: Table 1 (S1..S4, attitude); nav: the navigation benchmark "
                        "N1..N4 (guided goto, offboard velocity with yaw, AUTO mission with "
                        "splines, the mission in wind), docs/howto/nav-bench.md; failures: "
                        "F1..F12, one fault class each (GNSS, baro, compass, gyro, accel, "
                        "motor, battery, SIL link, GCS loss, RC loss, a motor failing), "
                        "docs/howto/failure-bench.md "
                        "(default %(default)s)")
    add_campaign_arguments(p)
    p.add_argument("--fc", default="ours", metavar="ours|ardupilot|px4|ours,ardupilot,px4",
                   help="flight controller(s): our SIL FC, ArduCopter SITL over its JSON "
                        "interface, PX4 SITL over MAVLink HIL, or several side by side in one "
                        "Table 1 (default %(default)s); a missing binary is an error")
    p.add_argument("--arducopter", default=None, metavar="PATH",
                   help="--fc ardupilot: the arducopter SITL binary (default: "
                        "$SILBRIDGE_ARDUCOPTER, then `arducopter` on PATH)")
    add_deprecated_alias(p, "--sitl", "--arducopter")
    p.add_argument("--speed", type=float, default=RunSpec.sitl_speedup, metavar="X",
                   help="--fc ardupilot: SITL's --speedup (lockstep either way; higher only "
                        "lets SITL run ahead of the wall clock) (default %(default)g); "
                        f"--suite nav: every FC's times real time (default there {NAV_SPEED:g})")
    add_deprecated_alias(p, "--sitl-speedup", "--speed")
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
    """(scenarios, windows, params) of `bench` and `ablate`, every one checked before any
    run starts; the windows fitted to --duration (tools/benchmark/windows_fit.py)."""
    if args.runs < 1:
        raise CampaignError("--runs must be >= 1")
    check_executor(args.executor, args.jobs, args.ray_address)   # Ray's extra first of all
    if args.duration <= 0:
        raise CampaignError("--duration must be > 0")
    scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    if not scenarios:
        raise CampaignError("--scenarios is empty: name at least one, e.g. S1")
    given = {"warmup": args.warmup, "transient": args.transient, "analysis": args.analysis,
             "yaw": args.yaw_window}
    fitted, note = fit_windows(args.duration, {name: None if win is getattr(WINDOWS, name)
                                               else win for name, win in given.items()})
    command = getattr(args, "command", None) or "bench"   # ablate shares these inputs

    def say(line: str) -> None:
        print(f"{command}: {line}", file=sys.stderr)
    if note:
        say(note)
    windows = (fitted.warmup, fitted.transient, fitted.analysis, fitted.yaw)
    params = tuple(sorted(run_params(args.param_file, args.param, say=say).items()))
    return scenarios, windows, params


def windows_dict(windows) -> dict:
    """The windows scored with, by name, for table1.json and ablation.json."""
    return dict(zip(WINDOW_FLAGS, ([a, b] for a, b in windows)))


def _autopilot_binaries(args, fcs: list[str]) -> tuple[str | None, str | None]:
    """(arducopter, px4) for the controllers asked for: a missing one is an error with the
    way to build it, before any run; a binary or speed given for no such run is refused."""
    speed_given = args.speed != RunSpec.sitl_speedup
    for flag, given, fc in (("--arducopter", args.arducopter is not None, "ardupilot"),
                            ("--speed", speed_given, "ardupilot"),
                            ("--px4", args.px4 is not None, "px4")):
        if given and fc not in fcs:
            raise CampaignError(f"{flag} is for --fc {fc} runs: add {fc} to --fc, or leave "
                                f"{flag} out")
    arducopter = px4 = None
    if "ardupilot" in fcs:
        from silbridge.tools.autopilots.ardupilot.sitl import require_arducopter
        arducopter = require_arducopter(args.arducopter)
    if "px4" in fcs:
        from silbridge.tools.autopilots.px4.sitl import require_px4
        px4 = require_px4(args.px4)[0]
    return arducopter, px4


def run(args) -> int:
    fcs = fc_choice(args.fc)
    if args.suite in ("nav", "failures"):
        return _run_nav(args, fcs)
    sitl, px4 = _autopilot_binaries(args, fcs)
    scenarios, windows, params = campaign_inputs(args)
    ours_only = [f for f, given in (("--param/--params", bool(params)),
                                    ("--viz-hz", args.viz_hz != 0)) if given]
    if ours_only and "ours" not in fcs:
        raise CampaignError(f"{' and '.join(ours_only)}: for our FC's runs (ArduCopter and "
                            f"PX4 keep their own parameters and logs): add ours to --fc, or "
                            f"leave them out")
    if ours_only and len(fcs) > 1:
        print(f"bench: {' and '.join(ours_only)} apply to our FC's runs only", file=sys.stderr)
    out_dir = Path(args.out)
    specs = []
    for fc in fcs:
        # ArduCopter's parameters are its own: our FC's --param overrides go to ours only.
        specs += make_specs(scenarios, args.runs, args.duration, out_dir, base_seed=args.seed,
                            imu_hz=args.imu_hz, params=params if fc == "ours" else (),
                            windows=windows, keep_logs=args.keep_logs, fc=fc, sitl=sitl,
                            sitl_speedup=args.speed, viz_hz=args.viz_hz, px4=px4,
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
                  "windows": windows_dict(windows),
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


def _run_nav(args, fcs: list[str]) -> int:
    """--suite nav (tools/benchmark/nav/command.py) and --suite failures
    (tools/benchmark/failures/command.py): --speed is every FC's real-time factor there;
    the binaries are checked before any run, as for the paper suite."""
    if args.suite == "failures":
        from silbridge.tools.benchmark.failures.command import run_failures as run_nav
    else:
        from silbridge.tools.benchmark.nav.command import run_nav

    speed_given = args.speed != RunSpec.sitl_speedup
    saved, args.speed = args.speed, RunSpec.sitl_speedup   # not an ArduCopter-only flag here
    sitl, px4 = _autopilot_binaries(args, fcs)
    args.speed = saved
    paper = {"--duration": (args.duration, PROTOCOL_S), "--imu-hz": (args.imu_hz, None),
             "--viz-hz": (args.viz_hz, 0.0)}
    for name, flag in WINDOW_FLAGS.items():   # a default window is the Windows tuple itself
        value = getattr(args, "yaw_window" if name == "yaw" else name)
        paper[flag] = (value, getattr(WINDOWS, name)) if value is getattr(WINDOWS, name) \
            else (value, None)
    return run_nav(args, paper, fcs, sitl, px4, speed_given)

