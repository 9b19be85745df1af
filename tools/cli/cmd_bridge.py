"""`silbridge bridge`: the simulator program (owns the segment, waits for `silbridge fc`).

With our FC, the FC's options given here (--param, --feature-off, --params) are handed to
the `silbridge fc` that attaches (tools/loop/fc_handover.py). ArduPilot and PX4 keep their
own parameters, and some options mean nothing for their links: those are refused, never
dropped.
"""

from __future__ import annotations

import json
import math
import sys

from silbridge.bridge.bridge_driver import prepare_segment, run_bridge

from silbridge.tools.loop.fc_handover import untaken, write_handover
from silbridge.tools.loop.fc_param_events import param_at_args, param_events
from silbridge.tools.loop.flight import segment_unlinker, bridge_config, make_simulator, summarise
from silbridge.tools.loop.stop_signals import STOP
from silbridge.tools.loop.transport_wiring import HIL_PORT, bridge_address, bridge_segment
from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.cli.flight_args import (
    OptionError,
    add_flight_arguments,
    check_link_addr,
    options_from_args,
)

HELP = "the simulator program: JSBSim + sensors, publishes to the SIL FC over shared memory"

def add_arguments(p) -> None:
    from silbridge.bridge.autopilots.ardupilot.json_protocol import DEFAULT_PORT, PORT_STRIDE

    add_flight_arguments(p, processes=False, link_help=(
        f"; --fc ardupilot: where SITL sends its servo packets (default "
        f"127.0.0.1:{DEFAULT_PORT}); --fc px4: where PX4 connects"))
    p.add_argument("--fc", choices=("ours", "ardupilot", "px4"), default="ours",
                   help="the flight controller: our SIL FC over the segment, "
                        "ArduPilot SITL (`arducopter --model JSON`) over its JSON interface, or "
                        "PX4 (SITL or a board in HIL) over its MAVLink simulator link "
                        "(default %(default)s)")
    p.add_argument("-I", "--sitl-instance", type=int, default=None, metavar="N",
                   help=f"the autopilot's instance number, as sim_vehicle.py -I N and PX4 -i N: "
                        f"link port {HIL_PORT} + N (ours over udp/tcp, px4), or "
                        f"{DEFAULT_PORT} + {PORT_STRIDE} N (ardupilot) (default: instance 0)")
    add_deprecated_alias(p, "--sitl-address", "--link-addr")


def run(args) -> int:
    _check_instance(args)
    if args.fc == "ardupilot":
        return _run_ardupilot(args)
    if args.fc == "px4":
        return _run_px4(args)
    opts = options_from_args(args)
    check_link_addr(opts.transport, args.link_addr)
    opts.instance = opts.instance or "silbridge"
    if opts.hil_addr is None and args.sitl_instance is not None:
        opts.hil_addr = f"127.0.0.1:{HIL_PORT + args.sitl_instance}"
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    # The scenario's [[fc_param]] changes are the FC's to make: say how to hand them over.
    timed = "".join(f" {a}" for a in param_at_args(param_events(sc)))
    # Written before the segment exists: an FC attaches as soon as it does.
    handover = write_handover(opts.instance, params=opts.params or {},
                              features_off=opts.features_off, param_file=opts.param_file)
    res = None
    try:
        with bridge_segment(opts.transport, opts.instance, sim, hil_addr=opts.hil_addr) as seg:
            prepare_segment(seg, sim, cfg)
            if opts.transport == "shm":
                out(f"bridge: segment '{opts.instance}' ready; start `silbridge fc --instance "
                    f"{opts.instance}{timed}`")
            else:
                out(f"bridge: MAVLink HIL on {opts.transport} {bridge_address(seg)}; start "
                    f"`silbridge fc --transport {opts.transport} --link-addr "
                    f"{bridge_address(seg)} --instance {opts.instance}{timed}` "
                    f"(or a PX4 SITL / HIL autopilot)")
            if not math.isfinite(cfg.duration_s):
                out("bridge: real time until stopped (Ctrl-C); --duration S ends it sooner")
            from silbridge.fc_sil.sim_notice import NoticeWriter    # rate reports -> FC
            notices = None if cfg.lockstep else NoticeWriter(opts.instance)
            with STOP.polling(), STOP.emergency(segment_unlinker(seg)):
                res = run_bridge(sim, seg, cfg, out=out, stop=STOP, notify=notices)
            if notices is not None:     # the FC has read the end figures (it said DONE)
                notices.remove()
    finally:
        if untaken(handover) and res is not None:
            print("bridge: no `silbridge fc` took --param/--feature-off/--params (a foreign "
                  "autopilot flew?); they were not applied", file=sys.stderr)
    summary = summarise(opts, sc, sim, res, {})
    if args.json:
        print(json.dumps(summary))
    else:
        from silbridge.tools.loop.flight import print_summary
        print_summary(summary)
    return STOP.exit_code(1 if summary["crashed"] else 0)


def _check_instance(args) -> None:
    n = args.sitl_instance
    if n is None:
        return
    if n < 0:
        raise OptionError("-I/--sitl-instance must be >= 0")
    if args.link_addr is not None:
        raise OptionError("give -I N (the instance's default port) or --link-addr, not both")
    if args.fc == "ours" and args.transport == "shm":
        raise OptionError("-I N moves the link port: with shared memory there is none; use "
                          "--instance NAME, or --transport udp/tcp")


def _refuse(args, opts, fc: str, extra=()) -> None:
    """Options that cannot act with a foreign autopilot: a clear error, never a silent drop."""
    owner = {"ardupilot": "ArduCopter", "px4": "PX4"}[fc]
    refused = [(f"--param/--feature-off/--params set our FC's parameters; {owner} keeps its "
                f"own (set them there: its parameter file or a GCS)",
                bool(opts.params or opts.features_off or opts.param_file)),
               ("--transport: the link is the autopilot's own", opts.transport != "shm"),
               ("--busy-wait: this link is not paced by our loop", opts.busy_wait),
               *extra]
    for what, given in refused:
        if given:
            raise OptionError(f"{what}; leave it out with --fc {fc}")


def _run_ardupilot(args) -> int:
    """Our physics as ArduPilot SITL's JSON backend (lockstep: SITL sets the pace)."""
    from silbridge.tools.autopilots.ardupilot.bridge_cmd import run_ardupilot_bridge

    opts = options_from_args(args)
    _refuse(args, opts, "ardupilot", extra=[
        ("--realtime/--speed: SITL paces the JSON link (its --speedup)", not opts.lockstep)])
    return run_ardupilot_bridge(args)


def _run_px4(args) -> int:
    """PX4 over its simulator link (tools/autopilots/px4/bridge_cmd.py)."""
    from silbridge.tools.autopilots.px4.bridge_cmd import run_px4_bridge

    opts = options_from_args(args)
    _refuse(args, opts, "px4", extra=[
        ("--duration inf: the PX4 link runs a finite duration (give seconds)",
         args.duration is not None and math.isinf(args.duration))])
    if args.sitl_instance is not None:
        args.link_addr = f"127.0.0.1:{HIL_PORT + args.sitl_instance}"
    if args.duration is None and not opts.lockstep:
        # The PX4 link cannot run until stopped: it keeps the scenario's duration, and says so.
        from silbridge.tools.loop.fc_param_events import load_flight_scenario
        args.duration = load_flight_scenario(opts.scenario, seed=opts.seed).duration_s
        print(f"bridge: --fc px4 runs the scenario's {args.duration:g} s of sim time; give "
              f"--duration S for longer", file=sys.stderr)
    return run_px4_bridge(args)
