"""How fast PX4 runs on our physics in lockstep, against PX4's own SIH simulator, one run.

    python -m silbridge.tools.autopilots.px4.speed [--px4 PATH] [--window 10] [--json]

Two PX4 instances, one after the other, on the same machine and binary, each measured the
same way: PX4's own clock (ATTITUDE.time_boot_ms on its offboard link) over `--window`
seconds of wall time, after `--warmup` seconds from the first message (boot); the vehicle
sits disarmed on the ground in both.
- SIH: airframe 10040_sihsim_quadx, PX4's built-in simulator, with PX4_SIM_SPEED_FACTOR set
  far above what the machine can reach (`--sih-factor`, default 1000), so it runs as fast as
  it can;
- ours: airframe 10016_none_iris in lockstep on our physics (bridge/autopilots/px4/server.py), which
  steps as fast as PX4 answers.
Printed: both speeds (sim seconds per wall second) and their ratio, ours / SIH.
"""

from __future__ import annotations

import argparse
import json
import select
import socket
import sys
import threading
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.link_spin import spin_budget_us
from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.autopilots.px4.server import Px4HilServer
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_channel import make_codec

from silbridge.tools.autopilots.px4 import sitl as sp
from silbridge.tools.autopilots.common.run import AutopilotRun

SIH_AIRFRAME = 10040


class ClockProbe(threading.Thread):
    """PX4's clock as seen on its offboard link: (wall s, time_boot_ms) from ATTITUDE."""

    def __init__(self, instance: int):
        super().__init__(daemon=True)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", sp.OFFBOARD_REMOTE_BASE + instance))
        self.peer = ("127.0.0.1", sp.OFFBOARD_LOCAL_BASE + instance)
        self.codec = mav.MAVLink(None, srcSystem=254, srcComponent=191)
        self.codec.robust_parsing = True
        self.samples: list = []
        self.halt = threading.Event()

    def run(self) -> None:
        asked = False
        while not self.halt.is_set():
            r, _, _ = select.select([self.sock], [], [], 0.05)
            if not r:
                continue
            data = self.sock.recv(65536)
            now = time.monotonic()
            for m in self.codec.parse_buffer(data) or []:
                if m.get_type() == "HEARTBEAT" and not asked:
                    asked = True
                    self.sock.sendto(self.codec.command_long_encode(
                        m.get_srcSystem(), 1, mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                        mav.MAVLINK_MSG_ID_ATTITUDE, 20000, 0, 0, 0, 0, 0).pack(self.codec),
                        self.peer)
                elif m.get_type() == "ATTITUDE":
                    self.samples.append((now, m.time_boot_ms / 1000.0))
        self.sock.close()

    def stop(self) -> None:
        self.halt.set()
        self.join(2.0)

    def speed(self, warmup_s: float, window_s: float) -> float | None:
        s = self.samples
        if not s:
            return None
        t0 = s[0][0] + warmup_s
        inside = [x for x in s if t0 <= x[0] <= t0 + window_s]
        if len(inside) < 2:
            return None
        (w0, p0), (w1, p1) = inside[0], inside[-1]
        return (p1 - p0) / (w1 - w0)

    def done(self, warmup_s: float, window_s: float) -> bool:
        return bool(self.samples) and time.monotonic() > self.samples[0][0] + warmup_s + window_s


def measure(binary: str, etc: str, *, ours: bool, warmup_s: float, window_s: float,
            sih_factor: float) -> dict:
    run = AutopilotRun(sp.PX4, "silbridge-px4-speed-")
    n, work = run.instance, run.workdir
    try:
        probe = ClockProbe(n)
    except BaseException:
        run.close()
        raise
    server = None
    try:
        probe.start()
        budget = warmup_s + window_s + 60.0
        if ours:
            sc = load_scenario("S1")
            phys = Px4Physics(lambda: Simulator(sc), make_codec(1, 51))
            server = Px4HilServer(phys, ("127.0.0.1", sp.SIM_TCP_BASE + n))
            run.launch(sp.start_px4, binary, etc, n, work, params=sp.px4_params(phys.sim, sc))
            server.serve(1e6, stop=run.stop_when(lambda: probe.done(warmup_s, window_s)),
                         connect_timeout_s=30.0, spin_us=spin_budget_us(1))
        else:
            run.launch(sp.start_px4, binary, etc, n, work, params={}, speed_factor=sih_factor,
                       autostart=SIH_AIRFRAME)
            end = time.monotonic() + budget
            while not probe.done(warmup_s, window_s) and time.monotonic() < end \
                    and not run.exited():
                time.sleep(0.1)
    finally:
        run.close(probe, server)
    speed = probe.speed(warmup_s, window_s)
    if speed is None:
        raise sp.Px4Error(f"no clock from PX4 ({'ours' if ours else 'SIH'}) on its offboard "
                          f"link; its output: {run.tail}")
    return {"sim_s_per_wall_s": speed, "samples": len(probe.samples)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m silbridge.tools.autopilots.px4.speed",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("--px4", default=None, metavar="PATH",
                    help="px4 binary (default $SILBRIDGE_PX4, then PATH)")
    ap.add_argument("--warmup", type=float, default=4.0, metavar="S")
    ap.add_argument("--window", type=float, default=10.0, metavar="S")
    ap.add_argument("--sih-factor", type=float, default=1000.0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    try:
        binary, etc = sp.require_px4(args.px4)
    except sp.Px4Error as e:
        print(f"{ap.prog}: {e}", file=sys.stderr)
        return 2
    sih = measure(binary, etc, ours=False, warmup_s=args.warmup, window_s=args.window,
                  sih_factor=args.sih_factor)
    ours = measure(binary, etc, ours=True, warmup_s=args.warmup, window_s=args.window,
                   sih_factor=args.sih_factor)
    ratio = ours["sim_s_per_wall_s"] / sih["sim_s_per_wall_s"]
    out = {"sih": sih, "silbridge_lockstep": ours, "ratio": ratio, "window_s": args.window,
           "warmup_s": args.warmup, "sih_factor": args.sih_factor, "px4": binary}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"PX4 on its SIH simulator:      {sih['sim_s_per_wall_s']:6.2f}x real time")
        print(f"PX4 on silbridge (lockstep):   {ours['sim_s_per_wall_s']:6.2f}x real time")
        print(f"ratio silbridge / SIH:         {100 * ratio:6.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
