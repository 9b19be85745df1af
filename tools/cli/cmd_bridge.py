"""`silbridge bridge`: the simulator program (owns the segment, waits for `silbridge fc`)."""

from __future__ import annotations

import json
import sys

from silbridge.bridge.runner_main import prepare_segment, run_bridge

from silbridge.tools.loop.fc_param_events import param_at_args, param_events
from silbridge.tools.loop.flight import segment_unlinker, bridge_config, make_simulator, summarise
from silbridge.tools.loop.stop_signals import STOP
from silbridge.tools.loop.transport_wiring import bridge_address, bridge_segment
from silbridge.tools.cli.flight_args import add_flight_arguments, options_from_args

HELP = "the simulator program: JSBSim + sensors, publishes to the SIL FC over shared memory"


def add_arguments(p) -> None:
    add_flight_arguments(p, processes=False)
    p.add_argument("--fc", choices=("ours", "ardupilot", "px4"), default="ours",
                   help="the flight controller: our SIL FC over the segment (default), "
                        "ArduPilot SITL (`arducopter --model JSON`) over its JSON interface, or "
                        "PX4 (SITL or a board in HIL) over its MAVLink simulator link")
    p.add_argument("--sitl-address", default=None, metavar="HOST:PORT",
                   help="--fc ardupilot: where SITL sends servo packets (default "
                        "127.0.0.1:9002, SITL instance 0; instance N uses 9002 + 10 N)")


def run(args) -> int:
    if args.fc == "ardupilot":
        return _run_ardupilot(args)
    if args.fc == "px4":
        from silbridge.tools.autopilots.px4_bridge import run_px4_bridge
        return run_px4_bridge(args)
    opts = options_from_args(args)
    opts.instance = opts.instance or "silbridge"
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    # The scenario's [[fc_param]] changes are the FC's to make: say how to hand them over.
    timed = "".join(f" {a}" for a in param_at_args(param_events(sc)))
    with bridge_segment(opts.transport, opts.instance, sim, hil_addr=opts.hil_addr) as seg:
        prepare_segment(seg, sim, cfg)
        if opts.transport == "shm":
            out(f"bridge: segment '{opts.instance}' ready; start `silbridge fc --instance "
                f"{opts.instance}{timed}`")
        else:
            out(f"bridge: MAVLink HIL on {opts.transport} {bridge_address(seg)}; start "
                f"`silbridge fc --transport {opts.transport} --hil-addr {bridge_address(seg)}"
                f"{timed}` (or a PX4 SITL / HIL autopilot)")
        with STOP.polling(), STOP.emergency(segment_unlinker(seg)):
            res = run_bridge(sim, seg, cfg, out=out, stop=STOP)
    summary = summarise(opts, sc, sim, res, {})
    if args.json:
        print(json.dumps(summary))
    else:
        from silbridge.tools.loop.flight import print_summary
        print_summary(summary)
    return STOP.exit_code(1 if summary["crashed"] else 0)


def _run_ardupilot(args) -> int:
    """Our physics as ArduPilot SITL's JSON backend (lockstep: SITL sets the pace)."""
    from silbridge.tools.autopilots.ardupilot_flight import serve_bridge

    opts = options_from_args(args)
    ignored = [flag for flag, given in (
        ("--realtime/--speed (SITL paces the JSON link: its --speedup)", not opts.lockstep),
        ("--transport/--hil-addr", opts.transport != "shm"),
        ("--param/--feature-off (ArduCopter keeps its own parameters)",
         bool(opts.params or opts.features_off))) if given]
    for flag in ignored:
        print(f"bridge: {flag} ignored with --fc ardupilot", file=sys.stderr)
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    summary = serve_bridge(opts.scenario, seed=opts.seed, imu_hz=opts.imu_hz,
                           duration_s=opts.duration_s, sitl_address=args.sitl_address, out=out)
    if args.json:
        print(json.dumps(summary))
    else:
        link = summary["json_link"]
        out(f"ArduPilot SITL: {summary['sim_s']:.2f} s simulated in "
            f"{summary['wall_s']:.2f} s wall; "
            f"{link['packets']} servo packets, {link['duplicates']} resent, "
            f"{link['dropped_frames']} lost, {link['resets']} SITL restarts; "
            f"crashed {summary['crashed']}")
    return 1 if summary["crashed"] else 0
