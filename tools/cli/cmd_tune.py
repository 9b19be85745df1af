"""`silbridge tune`: frequency responses, stability margins, step responses, an
automatic gain search and the harmonic notch setup, on the same C core the benchmark
flies.

    silbridge tune sysid --axis roll[,pitch,yaw] [--inject output|input|both]
    silbridge tune step  --axis roll[,pitch,yaw]
    silbridge tune auto  --axis roll,pitch --out DIR [--trials N] [--compare FILE.parm]
    silbridge tune anchor --axis roll,pitch [--ours FILE.parm]
    silbridge tune notch [LOG] [--scenario V2]

Every form takes --json (one JSON object on stdout) and writes its report
(index.html, report.md, PNG figures, summary.json; notch: notch.parm, the two logs and
summary.json) to --out.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.tune import tune_defaults as D

HELP = "identify and tune the attitude loops: sweeps, margins, steps, autotune, notch"
# tune notch without a log: the scenario with a vibration problem (V2, a bent prop)
NOTCH_SCENARIO = "V2"


def _common(p, default_out: str) -> None:
    p.add_argument("--axis", default="roll",
                   help="roll, pitch, yaw or a comma list (default %(default)s)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="FC parameter for every flight (repeatable; applied after --params)")
    p.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file whose values every flight uses (read only)")
    p.add_argument("--seed", type=int, default=1, help="scenario seed (default %(default)s)")
    p.add_argument("--jobs", type=int, default=None,
                   help="parallel flights: the local pool, or the CPUs of the Ray started "
                        "here (default: CPU count)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local process pool or a Ray cluster (default %(default)s)")
    p.add_argument("--ray-address", default=None,
                   help="Ray address for --executor ray (default: start a local Ray)")
    p.add_argument("--out", default=default_out, help="report folder (default %(default)s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_arguments(p) -> None:
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    s = sub.add_parser("sysid", help="frequency sweep: plant, loops, margins, bandwidth")
    _common(s, "tune-out/sysid")
    s.add_argument("--inject", choices=("output", "input", "both"), default="both",
                   help="mixer input (margins), rate target (bandwidth) or both "
                        "(default %(default)s)")
    for flag, default, what in (
            ("--f-start", D.SWEEP_F_START_HZ, "SID_F_START_HZ [Hz]"),
            ("--f-stop", D.SWEEP_F_STOP_HZ, "SID_F_STOP_HZ [Hz]"),
            ("--t-rec", D.SWEEP_T_REC_S, "SID_T_REC [s]"),
            ("--fade-in", D.SWEEP_T_FADE_IN_S, "SID_T_FADE_IN [s]"),
            ("--magnitude-rate", D.SWEEP_MAGNITUDE_RATE_DPS,
             "SID_MAGNITUDE of the rate sweep [deg/s]"),
            ("--magnitude-mixer", D.SWEEP_MAGNITUDE_MIXER,
             "SID_MAGNITUDE of the mixer sweep [0-1]")):
        s.add_argument(flag, type=float, default=default, help=what + " (default %(default)g)")
    t = sub.add_parser("step", help="step and doublet responses per axis")
    _common(t, "tune-out/step")
    t.add_argument("--amplitude", type=float, default=D.STEP_AMPLITUDE_DEG,
                   help="step size [deg] (default %(default)g)")
    t.add_argument("--hold", type=float, default=D.STEP_HOLD_S,
                   help="hold per level [s] (default %(default)g)")
    t.add_argument("--repeat", type=int, default=D.STEP_REPEAT,
                   help="doublets per axis (default %(default)s)")
    a = sub.add_parser("auto", help="search gains and filters; write a .parm and Table 1")
    _common(a, "tune-out/auto")
    a.add_argument("--trials", type=int, default=D.AUTO_TRIALS,
                   help="candidates flown (default %(default)s)")
    a.add_argument("--runs", type=int, default=D.AUTO_RUNS,
                   help="seeds per scenario in the before/after Table 1 (default %(default)s)")
    a.add_argument("--batch", type=int, default=D.AUTO_BATCH,
                   help="candidates flown together (default %(default)s)")
    a.add_argument("--pm-min", type=float, default=D.PM_MIN_DEG,
                   help="phase margin floor [deg] (default %(default)g)")
    a.add_argument("--gm-min", type=float, default=D.GM_MIN_DB,
                   help="gain margin floor [dB] (default %(default)g)")
    a.add_argument("--no-progress", action="store_true", help="no progress bar")
    a.add_argument("--compare", action="append", default=[], metavar="FILE.parm",
                   help="another gain set (e.g. tune anchor's arducopter_autotune.parm) scored "
                        "beside the defaults and ours on the same seeds; the tuned set must "
                        "beat it on S4 (repeatable)")
    a.add_argument("--keep-input-tc", action="store_true",
                   help="leave ATC_INPUT_TC out of the search (AUTOTUNE does not set it)")
    n = sub.add_parser("anchor", help="fly ArduCopter's own AUTOTUNE on our physics; its "
                                      "gains through Table 1 and the margins")
    _common(n, "tune-out/anchor")
    n.add_argument("--arducopter", default=None, metavar="PATH",
                   help="the arducopter SITL binary (default: $SILBRIDGE_ARDUCOPTER, then "
                        "`arducopter` on PATH); a missing one is an error")
    add_deprecated_alias(n, "--sitl", "--arducopter")
    n.add_argument("--runs", type=int, default=D.AUTO_RUNS,
                   help="seeds per scenario (default %(default)s)")
    n.add_argument("--ours", default=None, metavar="FILE",
                   help="our tuned .parm (tune auto) for a third column")
    n.add_argument("--aggr", type=float, default=D.AUTOTUNE_AGGR,
                   help="AUTOTUNE_AGGR (default %(default)g)")
    _add_notch(sub)


def _add_notch(sub) -> None:
    n = sub.add_parser("notch", help="harmonic notch and gyro filter from a hover's gyro "
                                     "spectrum; write a .parm, fly it, compare the noise")
    n.add_argument("log", nargs="?", default=None, metavar="LOG",
                   help="a `silbridge fly --log` hover; without it, fly --scenario first")
    n.add_argument("--scenario", default=NOTCH_SCENARIO,
                   help="scenario of the fresh hover without LOG (default %(default)s)")
    n.add_argument("--seed", type=int, default=1, help="its seed (default %(default)s)")
    n.add_argument("--duration", type=float, default=None,
                   help="its simulated seconds (default: the scenario's)")
    n.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="FC parameter for the flights this run makes (repeatable; applied "
                        "after --params; with LOG, the one after the proposal)")
    n.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file for the flights this run makes (read only)")
    n.add_argument("--mode", type=int, choices=(1, 3), default=None,
                   help="INS_HNTCH_MODE: 1 throttle, 3 ESC telemetry (default: 3 when the "
                        "log has ESC telemetry, else 1)")
    n.add_argument("--window", nargs=2, type=float, default=None, metavar=("A_S", "B_S"),
                   help="hover window in s of sim time (default: the scenario's steady "
                        "part, at most the log's second half)")
    n.add_argument("--crossover-hz", type=float, default=None, metavar="HZ",
                   help="also report the gyro filters' phase lag at this frequency (the "
                        "crossover `tune sysid` measured)")
    n.add_argument("--out", default="tune-out/notch",
                   help="folder for notch.parm, the logs and summary.json "
                        "(default %(default)s)")
    n.add_argument("--json", action="store_true", help="print one JSON object")


class TuneArgsError(Exception):
    user_facing = True


def _axes(text: str) -> tuple:
    from silbridge.tools.tune.tune_sysid import AXES
    axes = tuple(dict.fromkeys(a.strip().lower() for a in text.split(",") if a.strip()))
    bad = [a for a in axes if a not in AXES]
    if not axes or bad:
        raise TuneArgsError(f"--axis wants roll, pitch, yaw or a comma list, not {text!r}")
    return axes


def _base_params(args) -> dict:
    """--params FILE then --param, checked up front as the FC applies them (run_params)."""
    from silbridge.tools.benchmark.run_params import run_params
    return run_params(args.param_file, args.param,
                      say=lambda line: print(f"tune: {line}", file=sys.stderr))


def _clean(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


def _need(modules) -> None:
    from silbridge.tools.optional_deps import require
    require(modules, "tune", "`silbridge tune`")


def run(args) -> int:
    from silbridge.tools.benchmark.campaign import check_executor
    from silbridge.tools.tune.tune_exec import TaskPool

    if args.action == "notch":          # numpy only, no axes, no pool
        return _run_notch(args)

    _need(("scipy", "matplotlib") + (("optuna", "tqdm") if args.action == "auto" else ()))
    check_executor(args.executor, args.jobs, args.ray_address)
    axes = _axes(args.axis)
    base = _base_params(args)
    if args.action == "anchor":      # the binary first: a missing one stops before any flight
        from silbridge.tools.autopilots.ardupilot.sitl import require_arducopter
        args.arducopter = require_arducopter(args.arducopter)
        if args.ours and not Path(args.ours).is_file():
            raise TuneArgsError(f"--ours {args.ours}: no such file; give the .parm file "
                                f"`silbridge tune auto` wrote")
    out_dir = Path(args.out)
    say = (lambda s: print(s, file=sys.stderr)) if args.json else print
    with TaskPool(args.jobs, args.executor, args.ray_address) as pool:
        if args.action == "sysid":
            from silbridge.tools.tune.tune_cmds import run_sysid
            result = run_sysid(args, axes, base, out_dir, pool, say)
        elif args.action == "step":
            from silbridge.tools.tune.tune_cmds import run_step
            result = run_step(args, axes, base, out_dir, pool, say)
        elif args.action == "anchor":
            from silbridge.tools.tune.tune_anchor_cmd import run_anchor
            result = run_anchor(args, axes, base, out_dir, pool, say)
        else:
            from silbridge.tools.tune.tune_cmds import run_auto_cmd
            result = run_auto_cmd(args, axes, base, out_dir, pool, say)
    if args.json:
        print(json.dumps(_clean(result)))
    return 0


def _run_notch(args) -> int:
    from silbridge.tools.tune.tune_notch_cmd import run_notch
    say = (lambda s: print(s, file=sys.stderr)) if args.json else print
    result = run_notch(args, _base_params(args), Path(args.out), say)
    if args.json:
        print(json.dumps(_clean(result)))
    return 0
