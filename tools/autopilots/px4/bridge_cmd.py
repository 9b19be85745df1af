"""`silbridge bridge --fc px4`: our physics for a PX4 the user runs, in lockstep or real time
(`PX4_SYS_AUTOSTART=10016 px4 -i N`); they fly it from their own GCS (QGroundControl on UDP
14550).

    silbridge bridge --fc px4 --realtime --duration 600      # listens on 127.0.0.1:4560
    PX4_SYS_AUTOSTART=10016 build/px4_sitl_default/bin/px4   # in PX4-Autopilot; QGC on 14550

`--link-addr HOST:PORT` moves the listening address (PX4 instance N connects to 4560 + N);
`--link-addr serial:/dev/ttyACM0:921600` talks to a PX4 board in HIL mode over its serial
line instead (mavlink/hil/hil_serial.py). Lockstep is the default: PX4 in lockstep answers every
step. With --realtime the steps follow the wall clock, so a person can watch PX4 fly our
physics in QGroundControl.
"""

from __future__ import annotations

import sys

from silbridge.bridge.autopilots.px4.hil_messages import SIM_COMPID, SIM_SYSID
from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.autopilots.px4.server import Px4HilServer
from silbridge.mavlink.hil.hil_channel import make_codec, parse_addr

from silbridge.tools.autopilots.common.run import report_summary, run_summary, scenario_factory
from silbridge.tools.autopilots.px4.sitl import SIM_TCP_BASE
from silbridge.tools.cli.flight_args import options_from_args


def serve_px4(scenario: str, *, seed=None, imu_hz=None, duration_s=None, realtime=False,
              address=("127.0.0.1", SIM_TCP_BASE), channel=None, out=print) -> dict:
    """Our physics on PX4's simulator link until the scenario's duration of sim time."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    with Px4HilServer(phys, address, channel=channel) as server:
        where = (f"tcp {server.address[0]}:{server.address[1]}" if channel is None
                 else channel.name)
        n = server.address[1] - SIM_TCP_BASE if channel is None else 0
        out(f"bridge: PX4 simulator link on {where} ({'real time' if realtime else 'lockstep'}); "
            f"start `PX4_SYS_AUTOSTART=10016 px4 -i {n}` (PX4 v1.15, airframe none_iris)")
        res = server.serve(duration_s if duration_s is not None else sc.duration_s,
                           realtime=realtime, connect_timeout_s=600.0)
    return run_summary("px4", sc, res, imu_hz=phys.sim.imu_hz,
                       link={"hil_link": res.stats, "startup_check": res.startup_check})


def _line(summary: dict) -> str:
    link = summary["hil_link"]
    return (f"PX4: {summary['sim_s']:.2f} s simulated in {summary['wall_s']:.2f} s wall; "
            f"{link['px4_steps']} steps ({link['freewheel_steps']} before PX4's first reply), "
            f"{link['replies']} replies, {link['unanswered_steps']} unanswered, "
            f"{link['stale_replies']} stale; crashed {summary['crashed']}")


def run_px4_bridge(args) -> int:
    opts = options_from_args(args)
    # Options PX4 cannot take (--transport, --param, --feature-off) were refused by
    # `silbridge bridge` before this point (tools/cli/cmd_bridge.py).
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    addr = opts.hil_addr
    channel = None
    address = ("127.0.0.1", SIM_TCP_BASE)
    if addr and addr.startswith("serial:"):
        from silbridge.mavlink.hil.hil_serial import open_serial
        channel = open_serial(addr, make_codec(SIM_SYSID, SIM_COMPID))
    elif addr:
        address = parse_addr(addr)
    summary = serve_px4(opts.scenario, seed=opts.seed, imu_hz=opts.imu_hz,
                        duration_s=opts.duration_s, realtime=not opts.lockstep, address=address,
                        channel=channel, out=out)
    return report_summary(summary, as_json=args.json, out=out, line=_line)
