"""Record a real PX4 <-> bridge exchange into tests/tools/px4_exchange.json (the fixture of
tests/tools/test_px4_protocol.py): PX4's first messages, the freewheel start, lockstep replies.

    SILBRIDGE_PX4=.../bin/px4 python tests/tools/record_px4_exchange.py [--steps 120]

It runs the real bridge side (bridge/autopilots/px4/server.py on a Simulator of S1) against a real PX4
SITL and writes every frame of the first `--steps` lockstep steps in the order the bridge
sent or read them, hex-encoded, with the PX4 version string from its log.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import tempfile
from pathlib import Path

from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.autopilots.px4.server import Px4HilServer
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_channel import make_codec
from silbridge.tools.autopilots.px4 import sitl as sp

FIXTURE = Path(__file__).with_name("px4_exchange.json")


class Recorder:
    """Wraps the server's channel: every frame out and every message in, in order."""

    def __init__(self, channel, events: list, limit: int):
        self.ch = channel
        self.events = events
        self.limit = limit

    def __getattr__(self, name):
        return getattr(self.ch, name)

    def send(self, frames):
        if len(self.events) < self.limit:
            self.events.extend(["tx", f.hex()] for f in frames)
        return self.ch.send(frames)

    def receive(self, timeout_s=0.0):
        msgs = self.ch.receive(timeout_s)
        if len(self.events) < self.limit:
            self.events.extend(["rx", bytes(m.get_msgbuf()).hex()] for m in msgs)
        return msgs


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=120)
    args = ap.parse_args()
    binary, etc = sp.find_px4()
    sc = load_scenario("S1", seed=1)
    phys = Px4Physics(lambda: Simulator(sc), make_codec(1, 51))
    n = sp.pick_instance()
    work = tempfile.mkdtemp(prefix="px4-record-")
    events: list = []
    server = Px4HilServer(phys, ("127.0.0.1", sp.SIM_TCP_BASE + n))
    proc = sp.start_px4(binary, etc, n, work, params=sp.px4_params(phys.sim, sc))
    try:
        server._accept(30.0, None)
        server.channel = Recorder(server.channel, events, 10_000)
        def stop() -> bool:
            return phys.first_reply_us is not None and \
                phys.steps - phys.freewheel_steps >= args.steps
        server.serve(60.0, stop=stop)
    finally:
        sp.stop_px4(proc, n)
        server.close()
        sp.release_instance(n)
    text = open(os.path.join(work, "px4.log"), errors="replace").read()
    shutil.rmtree(work, ignore_errors=True)
    version = re.search(r"PX4 git-hash[^\n]*|px4 starting", text)
    FIXTURE.write_text(json.dumps({
        "source": "PX4 v1.15.4 SITL, airframe 10016_none_iris, against bridge/autopilots/px4/server.py "
                  "on scenario S1 (tests/tools/record_px4_exchange.py)",
        "px4_log_marker": version.group(0) if version else "",
        "step_us": 1_000_000 // phys.step_hz,
        "freewheel_steps": phys.freewheel_steps,
        "events": events}, indent=0) + "\n")
    print(f"{len(events)} frames, {phys.freewheel_steps} freewheel steps -> {FIXTURE}")


if __name__ == "__main__":
    main()
