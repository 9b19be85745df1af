"""One nav run on ArduCopter: a fresh ArduCopter SITL (--model JSON) on our physics in this
process (bridge/autopilots/ardupilot/physics.py, lockstep: SITL waits for each physics reply,
paced by its --speedup), the client on SITL's own MAVLink port (TCP 5760 + 10 N) in a
thread, and the ground truth of every physics step logged to MCAP (in_process.py), the
channels and clock our FC's log has: the same scoring reads both.

The client's clock is the physics time itself (`phys.sim.sim_ns`), the log's clock.
"""

from __future__ import annotations

import os

from silbridge.tools.benchmark.nav.in_process import GroundTruthLog, fly_foreign
from silbridge.tools.benchmark.nav.link import TcpLink
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight


def fly_ardupilot(plan: Plan, *, seed: int, log_path: str, speed: float, binary: str,
                  stop=None) -> Flight:
    from silbridge.bridge.autopilots.ardupilot.json_protocol import sitl_port
    from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
    from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer
    from silbridge.tools.autopilots.ardupilot import sitl
    from silbridge.tools.autopilots.common.run import AutopilotRun, scenario_factory

    sc, make_sim = scenario_factory(plan.physics_path, seed, None)
    run = AutopilotRun(sitl.ARDUCOPTER, "silbridge-nav-")
    port = sitl.MAVLINK_TCP_BASE + sitl.PORT_STRIDE * run.instance

    def start(parts):
        phys = ArduPilotPhysics(make_sim)
        defaults = sitl.sitl_defaults(phys.sim, phys.physics_hz)
        defaults_path = os.path.join(run.workdir, "silbridge-defaults.parm")
        sitl.write_defaults(defaults_path, defaults)
        parts.sink = phys.sink = GroundTruthLog(log_path, {
            "config": {"fc": "ardupilot", "seed": seed, "plan": plan.name,
                       "physics_hz": phys.physics_hz, "sitl_speedup": speed},
            "scenario": sc.to_dict(), "params": defaults,
            "software": {"arducopter": binary}})
        parts.server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(run.instance)))
        run.launch(sitl.start_sitl, binary, run.instance, run.workdir, speedup=speed,
                   home=sc.home, defaults_path=defaults_path)
        return phys, lambda: TcpLink(port, alive=lambda: not run.exited()), None

    return fly_foreign(plan, run, sc, start, stop=stop, connect_timeout_s=60.0)
