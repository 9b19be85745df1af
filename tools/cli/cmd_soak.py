"""`silbridge soak`: an hour (or minutes) of the real-time vehicle with a ground station
attached, sampled for growth (tools/soak/, docs/howto/soak.md)."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from silbridge.tools.cli.flight_args import OptionError, add_scenario_argument

# A sample a minute; short runs sample more often, so the late-step trend still has its
# points (tools/soak/verdict.py MIN_SAMPLES_FOR_TREND).
SAMPLE_S = 60.0
MIN_SAMPLES = 8

HELP = "hours of `silbridge sitl` with a busy ground station; fails on memory/fd/late growth"


def add_arguments(p: argparse.ArgumentParser) -> None:
    how_long = p.add_mutually_exclusive_group(required=True)
    how_long.add_argument("--hours", type=float, metavar="H", help="run for H wall hours")
    how_long.add_argument("--minutes", type=float, metavar="M", help="run for M wall minutes")
    p.add_argument("--sample-every", type=float, default=None, metavar="S",
                   help=f"wall seconds between samples (default: {SAMPLE_S:g}, or the run "
                        f"over {MIN_SAMPLES} when that is shorter)")
    p.add_argument("--action-every", type=float, default=5.0, metavar="S",
                   help="wall seconds between ground-station actions (default %(default)s)")
    add_scenario_argument(p)
    p.add_argument("--processes", type=int, choices=(1, 2), default=2,
                   help="bridge and FC in one process or two (default %(default)s)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for the log, the saved params, the vehicle's output and the "
                        "figure (default: a new temporary folder)")
    p.add_argument("--json", action="store_true",
                   help="print the result as one JSON object (sample lines go to stderr)")


def run(args) -> int:
    from silbridge.tools.soak.figures import write_figures
    from silbridge.tools.soak.run import SoakOptions, run_soak

    total_s = args.hours * 3600 if args.hours is not None else args.minutes * 60
    sample_s = min(SAMPLE_S, total_s / MIN_SAMPLES) if args.sample_every is None \
        else args.sample_every
    if total_s <= 0 or sample_s <= 0 or args.action_every <= 0:
        raise OptionError("--hours/--minutes, --sample-every and --action-every must be > 0")
    if sample_s * 2 > total_s:
        raise OptionError("the run must hold at least two samples: lower --sample-every")
    out_dir = Path(args.out or tempfile.mkdtemp(prefix="silbridge-soak-"))
    say = (lambda s: print(s, file=sys.stderr, flush=True)) if args.json else \
        (lambda s: print(s, flush=True))
    result = run_soak(SoakOptions(total_s=total_s, out_dir=out_dir, sample_s=sample_s,
                                  action_s=args.action_every, scenario=args.scenario,
                                  processes=args.processes), out=say)
    result["figures"] = write_figures(result, out_dir)
    (out_dir / "soak.json").write_text(json.dumps(result, indent=1))
    for c in result["checks"]:
        say(f"check {c['name']:<16} {'ok  ' if c['ok'] else 'FAIL'} {c['detail']}")
    say(f"soak: {'PASS' if result['ok'] else 'FAIL'} ({out_dir})")
    if args.json:
        print(json.dumps(result))
    return 0 if result["ok"] else 1
