"""`silbridge bridge`: the simulator program (owns the segment, waits for `silbridge fc`)."""

from __future__ import annotations

import json
import sys

from silbridge.bridge.runner_main import prepare_segment, run_bridge

from .flight import bridge_config, make_simulator, summarise
from .transport_wiring import bridge_address, bridge_segment
from .flight_args import add_flight_arguments, options_from_args

HELP = "the simulator program: JSBSim + sensors, publishes to the SIL FC over shared memory"


def add_arguments(p) -> None:
    add_flight_arguments(p, processes=False)


def run(args) -> int:
    opts = options_from_args(args)
    opts.instance = opts.instance or "silbridge"
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    with bridge_segment(opts.transport, opts.instance, sim, hil_addr=opts.hil_addr) as seg:
        prepare_segment(seg, sim, cfg)
        if opts.transport == "shm":
            out(f"bridge: segment '{opts.instance}' ready; start `silbridge fc --instance "
                f"{opts.instance}`")
        else:
            out(f"bridge: MAVLink HIL on {opts.transport} {bridge_address(seg)}; start "
                f"`silbridge fc --transport {opts.transport} --hil-addr {bridge_address(seg)}` "
                f"(or a PX4 SITL / HIL autopilot)")
        res = run_bridge(sim, seg, cfg, out=out)
    summary = summarise(opts, sc, sim, res, {})
    if args.json:
        print(json.dumps(summary))
    else:
        from .flight import print_summary
        print_summary(summary)
    return 1 if summary["crashed"] else 0
