"""`silbridge bridge --fc px4`: our physics for a PX4 the user runs, in lockstep or real time.

    silbridge bridge --fc px4 --realtime --duration 600      # listens on 127.0.0.1:4560
    PX4_SYS_AUTOSTART=10016 build/px4_sitl_default/bin/px4   # in PX4-Autopilot; QGC on 14550

`--link-addr HOST:PORT` moves the listening address (PX4 instance N connects to 4560 + N);
`--link-addr serial:/dev/ttyACM0:921600` talks to a PX4 board in HIL mode over its serial
line instead (mavlink/hil/hil_serial.py). Lockstep is the default: PX4 in lockstep answers every
step. With --realtime the steps follow the wall clock, so a person can watch PX4 fly our
physics in QGroundControl.
"""

from __future__ import annotations

import json
import sys

from silbridge.mavlink.hil.hil_channel import parse_addr

from silbridge.tools.cli.flight_args import options_from_args
from silbridge.tools.autopilots.px4_flight import serve_px4
from silbridge.tools.autopilots.sitl_px4 import SIM_TCP_BASE


def run_px4_bridge(args) -> int:
    opts = options_from_args(args)
    # Options PX4 cannot take (--transport, --param, --feature-off) were refused by
    # `silbridge bridge` before this point (tools/cli/cmd_bridge.py).
    out = (lambda s: print(s, file=sys.stderr)) if args.json else print
    addr = opts.hil_addr
    channel = None
    address = ("127.0.0.1", SIM_TCP_BASE)
    if addr and addr.startswith("serial:"):
        from silbridge.mavlink.hil.hil_channel import make_codec
        from silbridge.mavlink.hil.hil_serial import open_serial

        from silbridge.tools.autopilots.px4_flight import SIM_COMPID, SIM_SYSID
        channel = open_serial(addr, make_codec(SIM_SYSID, SIM_COMPID))
    elif addr:
        address = parse_addr(addr)
    summary = serve_px4(opts.scenario, seed=opts.seed, imu_hz=opts.imu_hz,
                        duration_s=opts.duration_s, realtime=not opts.lockstep, address=address,
                        channel=channel, out=out)
    if args.json:
        print(json.dumps(summary))
    else:
        link = summary["hil_link"]
        out(f"PX4: {summary['sim_s']:.2f} s simulated in {summary['wall_s']:.2f} s wall; "
            f"{link['px4_steps']} steps ({link['freewheel_steps']} before PX4's first reply), "
            f"{link['replies']} replies, {link['unanswered_steps']} unanswered, "
            f"{link['stale_replies']} stale; crashed {summary['crashed']}")
    return 1 if summary["crashed"] else 0
