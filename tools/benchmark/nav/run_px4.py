"""One nav run on PX4: a fresh PX4 SITL (v1.15, none_iris airframe) on our physics in this
process over its simulator link (MAVLink HIL on TCP 4560 + N, lockstep: bridge/px4_physics.py),
the client on PX4's offboard link (it sends to UDP 14540 + N and listens on 14580 + N) in a
thread, PX4's ways (tools/benchmark/nav/ways.py Px4Ways), the ground truth logged as for
ArduCopter (in_process.py). The client's clock is the physics time.

PX4 keeps its own pacing in lockstep (it waits for each physics step), so --speed does not
apply to it; its parameters are the paper suite's (tools/autopilots/sitl_px4.py px4_params:
our airframe, MIS_TAKEOFF_ALT = the plan's height, no RC).
"""

from __future__ import annotations

from silbridge.tools.benchmark.nav.in_process import (BOOT_SLACK_S, GroundTruthLog,
                                                      fly_autopilot_thread)
from silbridge.tools.benchmark.nav.link import UdpLink
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight
from silbridge.tools.benchmark.nav.ways import Px4Ways

_NS = 1_000_000_000
SIM_SYSID, SIM_COMPID = 1, 51     # our simulator on PX4's HIL link (tools/autopilots/px4_flight.py)


def _offboard_link(instance: int) -> UdpLink:
    from silbridge.tools.autopilots.sitl_px4 import OFFBOARD_LOCAL_BASE, OFFBOARD_REMOTE_BASE
    link = UdpLink(OFFBOARD_REMOTE_BASE + instance)
    link.peer = ("127.0.0.1", OFFBOARD_LOCAL_BASE + instance)
    return link


def fly_px4(plan: Plan, *, seed: int, log_path: str, speed: float, binary: str,
            stop=None) -> Flight:
    from silbridge.bridge.px4_physics import Px4Physics
    from silbridge.bridge.px4_server import Px4HilServer
    from silbridge.mavlink.hil.hil_channel import make_codec
    from silbridge.tools.autopilots.autopilot_run import AutopilotRun, scenario_factory
    from silbridge.tools.autopilots.sitl_px4 import (PX4, SIM_TCP_BASE, px4_params,
                                                     require_px4, start_px4)

    binary, etc = require_px4(binary)
    sc, make_sim = scenario_factory(plan.physics_path, seed, None)
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    p4 = px4_params(phys.sim, sc)
    run = AutopilotRun(PX4, "silbridge-nav-px4-")
    server = sink = None
    thread, out = None, {"done": False}
    try:
        sink = phys.sink = GroundTruthLog(log_path, {
            "config": {"fc": "px4", "seed": seed, "plan": plan.name,
                       "physics_hz": phys.sim.physics_hz},
            "scenario": sc.to_dict(), "params": p4, "software": {"px4": binary}})
        server = Px4HilServer(phys, ("127.0.0.1", SIM_TCP_BASE + run.instance))
        run.launch(start_px4, binary, etc, run.instance, run.workdir, params=p4)
        thread, out = fly_autopilot_thread(
            plan, lambda: _offboard_link(run.instance), (sc.home.lat_deg, sc.home.lon_deg),
            lambda: phys.sim.sim_ns / _NS, stop, Px4Ways())
        thread.start()
        server.serve(BOOT_SLACK_S + plan.budget_s, connect_timeout_s=30.0,
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
        flight.reason += f"; PX4's console: {run.tail}"
    return flight
