"""`silbridge tune`: frequency responses, stability margins, step responses and
an automatic gain search, on the same C core the benchmark flies.

    silbridge tune sysid --axis roll[,pitch,yaw] [--inject output|input|both]
    silbridge tune step  --axis roll[,pitch,yaw]
    silbridge tune auto  --axis roll,pitch --out DIR [--trials N] [--compare FILE.parm]
    silbridge tune anchor --axis roll,pitch [--ours FILE.parm]

Every form takes --json (one JSON object on stdout) and writes its report
(index.html, report.md, PNG figures, summary.json) to --out.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from silbridge.tools.cli.flight_args import parse_params

HELP = "identify and tune the attitude loops: sweeps, margins, steps, autotune"


def _common(p, default_out: str) -> None:
    p.add_argument("--axis", default="roll", help="roll, pitch, yaw or a comma list")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="FC parameter for every flight (repeatable)")
    p.add_argument("--params", dest="param_file", default=None, metavar="FILE",
                   help="ArduPilot .parm file whose values every flight uses")
    p.add_argument("--seed", type=int, default=1, help="scenario seed (default 1)")
    p.add_argument("--jobs", type=int, default=None, help="parallel flights (default: CPUs)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local process pool (default) or a Ray cluster")
    p.add_argument("--ray-address", default=None, help="Ray address for --executor ray")
    p.add_argument("--out", default=default_out, help=f"report folder (default {default_out})")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def add_arguments(p) -> None:
    sub = p.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    s = sub.add_parser("sysid", help="frequency sweep: plant, loops, margins, bandwidth")
    _common(s, "tune-out/sysid")
    s.add_argument("--inject", choices=("output", "input", "both"), default="both",
                   help="mixer input (margins), rate target (bandwidth) or both (default)")
    s.add_argument("--f-start", type=float, default=None, help="SID_F_START_HZ (default 0.5)")
    s.add_argument("--f-stop", type=float, default=None, help="SID_F_STOP_HZ (default 40)")
    s.add_argument("--t-rec", type=float, default=None, help="SID_T_REC [s] (default 40)")
    s.add_argument("--fade-in", type=float, default=None, help="SID_T_FADE_IN [s] (default 5)")
    s.add_argument("--magnitude-rate", type=float, default=None,
                   help="SID_MAGNITUDE of the rate sweep [deg/s] (default 15)")
    s.add_argument("--magnitude-mixer", type=float, default=None,
                   help="SID_MAGNITUDE of the mixer sweep [0-1] (default 0.05)")
    t = sub.add_parser("step", help="step and doublet responses per axis")
    _common(t, "tune-out/step")
    t.add_argument("--amplitude", type=float, default=10.0, help="step size [deg] (default 10)")
    t.add_argument("--hold", type=float, default=1.5, help="hold per level [s] (default 1.5)")
    t.add_argument("--repeat", type=int, default=2, help="doublets per axis (default 2)")
    a = sub.add_parser("auto", help="search gains and filters; write a .parm and Table 1")
    _common(a, "tune-out/auto")
    a.add_argument("--trials", type=int, default=60, help="candidates flown (default 60)")
    a.add_argument("--runs", type=int, default=3,
                   help="seeds per scenario in the before/after Table 1 (default 3)")
    a.add_argument("--batch", type=int, default=2, help="candidates flown together (default 2)")
    a.add_argument("--pm-min", type=float, default=45.0, help="phase margin floor [deg]")
    a.add_argument("--gm-min", type=float, default=6.0, help="gain margin floor [dB]")
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
    n.add_argument("--sitl", default=None, metavar="PATH",
                   help="arducopter binary (default: $SILBRIDGE_ARDUCOPTER, then PATH)")
    n.add_argument("--runs", type=int, default=3, help="seeds per scenario (default 3)")
    n.add_argument("--ours", default=None, metavar="FILE",
                   help="our tuned .parm (tune auto) for a third column")
    n.add_argument("--aggr", type=float, default=0.1, help="AUTOTUNE_AGGR (default 0.1)")


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
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.mavlink.gcs.params_file import load_parm

    params = {}
    if args.param_file:
        params.update({n.upper(): v for n, v in load_parm(args.param_file)})
    params.update(parse_params(args.param))
    core = FlightCore()
    for name, value in params.items():      # refuse what the FC would refuse, up front
        core.set_param(name, value)
    return params


def _clean(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    return v


def _need(modules) -> None:
    import importlib.util
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise TuneArgsError(f"`silbridge tune` needs {', '.join(missing)}: "
                            f"pip install 'silbridge[tune]'")


def run(args) -> int:
    from silbridge.tools.tune.tune_exec import TaskPool

    _need(("scipy", "matplotlib") + (("optuna", "tqdm") if args.action == "auto" else ()))
    axes = _axes(args.axis)
    base = _base_params(args)
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
