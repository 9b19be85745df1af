"""`silbridge fly`: the bridge and the SIL FC together, one flight.

The lockstep benchmark flight by default: no MAVLink, so a ground station sees nothing;
`silbridge sitl` is the vehicle for QGroundControl (said once on stderr).
"""

from __future__ import annotations

import json
import sys

from silbridge.tools.loop.flight import fly_one_process, fly_two_processes, print_summary
from silbridge.tools.cli.flight_args import (
    add_flight_arguments,
    add_mavlink_arguments,
    check_link_addr,
    options_from_args,
)

HELP = "fly the closed loop: simulator and SIL FC in one or two processes"

NO_MAVLINK_HINT = ("no MAVLink in lockstep: for a vehicle in QGroundControl run "
                   "`silbridge sitl`")


def add_arguments(p) -> None:
    add_flight_arguments(p, processes=True)
    add_mavlink_arguments(p)


def run(args) -> int:
    opts = options_from_args(args)
    check_link_addr(opts.transport, args.link_addr)
    if opts.lockstep and args.mavlink is None:
        print(f"silbridge fly: {NO_MAVLINK_HINT}", file=sys.stderr)
    return fly_and_report(opts, json_out=args.json)


def progress_printer(json_out: bool):
    """Progress lines go to stderr under --json so stdout stays one JSON object."""
    return (lambda s: print(s, file=sys.stderr)) if json_out else print


def fly_and_report(opts, *, json_out: bool) -> int:
    """One flight, its summary printed (or one JSON object), the exit status: 1 crashed,
    the signal's 130/143 when stopped (shared by `fly` and `sitl`)."""
    fly = fly_one_process if opts.processes == 1 else fly_two_processes
    summary = fly(opts, out=progress_printer(json_out))
    if json_out:
        print(json.dumps(summary))
    else:
        print_summary(summary)
    from silbridge.tools.loop.stop_signals import STOP
    return STOP.exit_code(1 if summary["crashed"] else 0)
