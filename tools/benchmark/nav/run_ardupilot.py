"""One nav run on ArduCopter: a fresh ArduCopter SITL (--model JSON) on our physics in this
process (bridge/ardupilot_physics.py, lockstep: SITL waits for each physics reply, paced by
its --speedup), the client on SITL's own MAVLink port (TCP 5760 + 10 N) in a thread, and
the ground truth of every physics step logged to MCAP (in_process.py), the channels and
clock our FC's log has: the same scoring reads both.

The client's clock is the physics time itself (`phys.sim.sim_ns`), the log's clock.
"""

from __future__ import annotations

import os

from silbridge.tools.benchmark.nav.in_process import (BOOT_SLACK_S, GroundTruthLog,
                                                      fly_autopilot_thread)
from silbridge.tools.benchmark.nav.link import TcpLink
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight

_NS = 1_000_000_000


def fly_ardupilot(plan: Plan, *, seed: int, log_path: str, speed: float, binary: str,
                  stop=None) -> Flight:
    from silbridge.bridge.ardupilot_json import sitl_port
    from silbridge.bridge.ardupilot_physics import ArduPilotPhysics
    from silbridge.bridge.ardupilot_server import JsonPhysicsServer
    from silbridge.tools.autopilots.autopilot_run import AutopilotRun, scenario_factory
    from silbridge.tools.autopilots.sitl_ardupilot import (ARDUCOPTER, MAVLINK_TCP_BASE,
                                                           PORT_STRIDE, sitl_defaults,
                                                           start_sitl, write_defaults)

    sc, make_sim = scenario_factory(plan.physics_path, seed, None)
    run = AutopilotRun(ARDUCOPTER, "silbridge-nav-")
    server = sink = None
    thread, out = None, {"done": False}
    try:
        phys = ArduPilotPhysics(make_sim)
        defaults = sitl_defaults(phys.sim, phys.physics_hz)
        defaults_path = os.path.join(run.workdir, "silbridge-defaults.parm")
        write_defaults(defaults_path, defaults)
        sink = phys.sink = GroundTruthLog(log_path, {
            "config": {"fc": "ardupilot", "seed": seed, "plan": plan.name,
                       "physics_hz": phys.physics_hz, "sitl_speedup": speed},
            "scenario": sc.to_dict(), "params": defaults,
            "software": {"arducopter": binary}})
        server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(run.instance)))
        run.launch(start_sitl, binary, run.instance, run.workdir, speedup=speed, home=sc.home,
                   defaults_path=defaults_path)
        port = MAVLINK_TCP_BASE + PORT_STRIDE * run.instance
        thread, out = fly_autopilot_thread(
            plan, lambda: TcpLink(port, alive=lambda: not run.exited()),
            (sc.home.lat_deg, sc.home.lon_deg), lambda: phys.sim.sim_ns / _NS, stop)
        thread.start()
        server.serve(BOOT_SLACK_S + plan.budget_s, connect_timeout_s=60.0,
                     stop=lambda: out["done"] or run.exited())
    except Exception as e:          # the physics side failed: a failed run, said why
        out.setdefault("flight", Flight(status="failed", reason=f"{type(e).__name__}: {e}"))
    finally:
        run.close(None, server)
        if thread is not None:
            thread.join(10.0)
        if sink is not None:
            sink.close()
    flight = out.get("flight") or Flight(status="failed", reason="the flight did not finish "
                                         "within the physics budget")
    if flight.status == "failed" and run.tail:
        flight.reason += f"; ArduCopter's console: {run.tail}"
    return flight
