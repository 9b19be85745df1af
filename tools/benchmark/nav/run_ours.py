"""One nav run on our FC: `silbridge fly --speed X --mavlink` (JSBSim and the SIL FC, one
process, real time times X) sending MAVLink to a UDP port the client binds, and logging
the run to MCAP; Ctrl-C (SIGINT) ends it, as a user ends `silbridge sitl`.

Our telemetry is stamped with the vehicle's sim time (time_boot_ms = sim ms since the run
started), the clock of the run log: the client paces itself on it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import uuid

from silbridge.tools.benchmark.nav.client import NavClient
from silbridge.tools.benchmark.nav.link import UdpLink, free_udp_port
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight, fly_plan

STOP_WALL_S = 30.0            # after SIGINT, the run may take this long to close its log


def fly_ours(plan: Plan, *, seed: int, log_path: str, speed: float, params=(),
             stop=None, client_cls=NavClient, fly=fly_plan) -> Flight:
    """params: (name, value) pairs of our FC's parameters, checked by the caller;
    client_cls and fly: the failure suite's client and flight (tools/benchmark/failures/)."""
    from silbridge.bridge.scenario import load_scenario

    sc = load_scenario(plan.physics_path, seed=seed)
    port = free_udp_port()
    link = UdpLink(port)
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--speed", f"{speed:g}",
           "--mavlink", "--no-default-gcs", "--gcs", f"udpout:127.0.0.1:{port}",
           "--scenario", plan.physics_path, "--seed", str(seed),
           "--duration", f"{sc.duration_s:g}", "--processes", "1", "--log", log_path,
           "--viz-hz", "0",
           "--instance", f"nav-{os.getpid()}-{uuid.uuid4().hex[:8]}"]
    for name, value in params:
        cmd += ["--param", f"{name}={value}"]
    err_path = log_path + ".stderr"
    with open(err_path, "w") as err:
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err,
                                stdin=subprocess.DEVNULL)
    try:
        client = client_cls(link, sc.home.lat_deg, sc.home.lon_deg, stop=stop)
        flight = fly(plan, client)
    finally:
        link.close()
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            proc.wait(STOP_WALL_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    if flight.status == "failed" and proc.returncode not in (0, 130, -signal.SIGINT):
        flight.reason += f"; silbridge fly exited {proc.returncode}: {_tail(err_path)}"
    return flight


def _tail(path: str, lines: int = 5) -> str:
    try:
        with open(path, errors="replace") as fh:
            return " | ".join(fh.read().strip().splitlines()[-lines:])
    except OSError:
        return ""
