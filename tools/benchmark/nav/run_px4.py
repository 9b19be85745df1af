"""One nav run on PX4: a fresh PX4 SITL (v1.15, none_iris airframe) on our physics in this
process over its simulator link (MAVLink HIL on TCP 4560 + N, lockstep:
bridge/autopilots/px4/physics.py), the client on PX4's offboard link (it sends to UDP
14540 + N and listens on 14580 + N) in a thread, PX4's ways (tools/benchmark/nav/ways.py
Px4Ways), the ground truth logged as for ArduCopter (in_process.py). The client's clock is
the physics time.

PX4 keeps its own pacing in lockstep (it waits for each physics step), so --speed does not
apply to it; its parameters are the paper suite's (tools/autopilots/px4/sitl.py px4_params:
our airframe, MIS_TAKEOFF_ALT = the plan's height, no RC).
"""

from __future__ import annotations

from silbridge.tools.benchmark.nav.in_process import GroundTruthLog, fly_foreign
from silbridge.tools.benchmark.nav.link import UdpLink
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight
from silbridge.tools.benchmark.nav.ways import Px4Ways


def _offboard_link(instance: int) -> UdpLink:
    from silbridge.tools.autopilots.px4.sitl import OFFBOARD_LOCAL_BASE, OFFBOARD_REMOTE_BASE
    link = UdpLink(OFFBOARD_REMOTE_BASE + instance)
    link.peer = ("127.0.0.1", OFFBOARD_LOCAL_BASE + instance)
    return link


def fly_px4(plan: Plan, *, seed: int, log_path: str, speed: float, binary: str,
            stop=None) -> Flight:
    from silbridge.bridge.autopilots.px4.hil_messages import SIM_COMPID, SIM_SYSID
    from silbridge.bridge.autopilots.px4.physics import Px4Physics
    from silbridge.bridge.autopilots.px4.server import Px4HilServer
    from silbridge.mavlink.hil.hil_channel import make_codec
    from silbridge.tools.autopilots.common.run import AutopilotRun, scenario_factory
    from silbridge.tools.autopilots.px4 import sitl

    binary, etc = sitl.require_px4(binary)
    sc, make_sim = scenario_factory(plan.physics_path, seed, None)
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    p4 = sitl.px4_params(phys.sim, sc)
    run = AutopilotRun(sitl.PX4, "silbridge-nav-px4-")

    def start(parts):
        parts.sink = phys.sink = GroundTruthLog(log_path, {
            "config": {"fc": "px4", "seed": seed, "plan": plan.name,
                       "physics_hz": phys.sim.physics_hz},
            "scenario": sc.to_dict(), "params": p4, "software": {"px4": binary}})
        parts.server = Px4HilServer(phys, ("127.0.0.1", sitl.SIM_TCP_BASE + run.instance))
        run.launch(sitl.start_px4, binary, etc, run.instance, run.workdir, params=p4)
        return phys, lambda: _offboard_link(run.instance), Px4Ways()

    return fly_foreign(plan, run, sc, start, stop=stop, connect_timeout_s=30.0)
