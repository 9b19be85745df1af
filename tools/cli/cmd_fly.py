"""`silbridge fly`: the bridge and the SIL FC together, one flight."""

from __future__ import annotations

import json
import sys

from silbridge.tools.loop.flight import fly_one_process, fly_two_processes, print_summary
from silbridge.tools.cli.flight_args import add_flight_arguments, add_mavlink_arguments, options_from_args

HELP = "fly the closed loop: simulator and SIL FC in one or two processes"


def add_arguments(p) -> None:
    add_flight_arguments(p, processes=True)
    add_mavlink_arguments(p)


def run(args) -> int:
    opts = options_from_args(args)
    # Progress lines go to stderr under --json so stdout stays one JSON object.
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    fly = fly_one_process if opts.processes == 1 else fly_two_processes
    summary = fly(opts, out=out)
    if args.json:
        print(json.dumps(summary))
    else:
        print_summary(summary)
    from silbridge.tools.loop.stop_signals import STOP
    return STOP.exit_code(1 if summary["crashed"] else 0)
