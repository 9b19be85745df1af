"""`silbridge bridge --fc ardupilot`: our physics as the JSON backend of a SITL the user runs.

    silbridge bridge --fc ardupilot --duration 600           # listens on UDP 127.0.0.1:9002
    arducopter --model JSON:127.0.0.1 --defaults ...          # the user's SITL (and GCS)

`--link-addr HOST:PORT` moves the listening address, `--sitl-instance N` listens where SITL
instance N sends (9002 + 10 N). SITL sets the pace (lockstep, its --speedup): options that
pace our side were refused by `silbridge bridge` before this point (tools/cli/cmd_bridge.py).
"""

from __future__ import annotations

import sys

from silbridge.bridge.autopilots.ardupilot.json_protocol import PORT_STRIDE, sitl_port
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer, parse_address

from silbridge.tools.autopilots.common.run import report_summary, run_summary, scenario_factory
from silbridge.tools.cli.flight_args import options_from_args


def serve_bridge(scenario: str, *, seed=None, imu_hz=None, duration_s=None,
                 sitl_address: str | None = None, out=print) -> dict:
    """Answer one SITL's servo packets until the scenario's duration of sim time."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    phys = ArduPilotPhysics(make_sim, note=lambda t: out(f"bridge: {t}"))
    address = parse_address(sitl_address, sitl_port(0))
    with JsonPhysicsServer(phys, address) as server:
        host, port = server.address
        n, off = divmod(port - sitl_port(0), PORT_STRIDE)
        inst = f" --instance {n}" if n >= 0 and off == 0 else ""
        out(f"bridge: ArduPilot JSON physics on udp {host}:{port}; start "
            f"`arducopter --model JSON:{host}{inst}` with SIM_RATE_HZ {phys.physics_hz:g}, "
            "FRAME_CLASS 1, FRAME_TYPE 1")
        res = server.serve(duration_s if duration_s is not None else sc.duration_s)
    return run_summary("ardupilot", sc, res, link={"json_link": res.stats},
                       imu_hz=phys.sim.imu_hz)


def _line(summary: dict) -> str:
    link = summary["json_link"]
    return (f"ArduPilot SITL: {summary['sim_s']:.2f} s simulated in "
            f"{summary['wall_s']:.2f} s wall; "
            f"{link['packets']} servo packets, {link['duplicates']} resent, "
            f"{link['dropped_frames']} lost, {link['resets']} SITL restarts; "
            f"crashed {summary['crashed']}")


def run_ardupilot_bridge(args) -> int:
    opts = options_from_args(args)
    address = opts.hil_addr
    if address is None and args.sitl_instance is not None:
        address = f"127.0.0.1:{sitl_port(args.sitl_instance)}"
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    summary = serve_bridge(opts.scenario, seed=opts.seed, imu_hz=opts.imu_hz,
                           duration_s=opts.duration_s, sitl_address=address, out=out)
    return report_summary(summary, as_json=args.json, out=out, line=_line)
