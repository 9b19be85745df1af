"""One failure run per autopilot, on the nav suite's runners (tools/benchmark/nav/run_*.py):
the plan's scenario (physics.toml + its [[failure]] entries) for the physics, the failsafe
settings of failsafe_params.py, the FailureClient and fly_failure for the flight.

Our FC: `silbridge fly --mavlink` with the settings as --param (nav's fly_ours). ArduCopter
and PX4: their SITL on our physics in this process (nav's fly_foreign), their settings and
boot SIM_* values (translate.py BOOT) in the defaults file / px4-rc.params; the physics
sink also sends the plan's SIM_* switches at their step (watch.py SimParamSwitcher).
"""

from __future__ import annotations

import os

from silbridge.tools.benchmark.failures import failsafe_params as fs
from silbridge.tools.benchmark.failures.plans import PlanRun
from silbridge.tools.benchmark.failures.script import FailureFlight, fly_failure
from silbridge.tools.benchmark.failures.translate import boot_params, sim_param_switches
from silbridge.tools.benchmark.failures.watch import FailureClient, SimParamSwitcher


def _as_failure_flight(flight) -> FailureFlight:
    """The flight, or a failed FailureFlight when the runner ended before the client did."""
    if isinstance(flight, FailureFlight):
        return flight
    return FailureFlight(status=flight.status, reason=flight.reason, end_s=flight.end_s)


def _client_cls(run: PlanRun, on_client=None):
    def make(link, lat, lon, clock=None, stop=None):
        c = FailureClient(link, lat, lon, clock=clock, stop=stop, mute=run.plan.client_windows())
        if on_client is not None:
            on_client(c)
        return c
    return make


class _Switching:
    """The SimParamSwitcher of a foreign run, made in start() and told the client once
    the flight thread has made it."""

    def __init__(self, fc: str, run: PlanRun, lat_deg: float):
        self.switches = sim_param_switches(fc, run.plan, lat_deg)
        self.sw: SimParamSwitcher | None = None
        self.client: FailureClient | None = None

    def sink(self, ground_truth) -> SimParamSwitcher:
        self.sw = SimParamSwitcher(ground_truth, self.switches)
        return self.sw

    def on_client(self, client) -> None:
        self.client = client
        if self.sw is not None:
            self.sw.client = client

    def done(self, flight: FailureFlight) -> FailureFlight:
        """The flight with the SIM_* switches sent; a flight the runner ended before the
        client did (the autopilot exited) gets the client's timeline so far."""
        if self.sw is not None:
            flight.sim_params = self.sw.sent
        if self.client is not None and not flight.timeline.modes:
            flight.timeline = self.client.timeline
        return flight


def fly_ours(run: PlanRun, *, seed: int, log_path: str, speed: float, params=(),
             stop=None) -> FailureFlight:
    from silbridge.tools.benchmark.nav.run_ours import fly_ours as nav_fly_ours
    settings = tuple(fs.OURS.items()) + tuple(params)
    return _as_failure_flight(nav_fly_ours(run, seed=seed, log_path=log_path, speed=speed,
                                           params=settings, stop=stop,
                                           client_cls=_client_cls(run), fly=fly_failure))


def fly_ardupilot(run: PlanRun, *, seed: int, log_path: str, speed: float, binary: str,
                  stop=None) -> FailureFlight:
    from silbridge.bridge.autopilots.ardupilot.json_protocol import sitl_port
    from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
    from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer
    from silbridge.tools.autopilots.ardupilot import sitl
    from silbridge.tools.autopilots.common.run import AutopilotRun, scenario_factory
    from silbridge.tools.benchmark.nav.in_process import GroundTruthLog, fly_foreign
    from silbridge.tools.benchmark.nav.link import TcpLink

    sc, make_sim = scenario_factory(run.physics_path, seed, None)
    ap = AutopilotRun(sitl.ARDUCOPTER, "silbridge-failures-")
    port = sitl.MAVLINK_TCP_BASE + sitl.PORT_STRIDE * ap.instance
    switching = _Switching("ardupilot", run, sc.home.lat_deg)

    def start(parts):
        phys = ArduPilotPhysics(make_sim)
        defaults = sitl.sitl_defaults(phys.sim, phys.physics_hz,
                                      {**fs.ARDUCOPTER, **boot_params("ardupilot", phys.sim)})
        defaults_path = os.path.join(ap.workdir, "silbridge-defaults.parm")
        sitl.write_defaults(defaults_path, defaults)
        parts.sink = GroundTruthLog(log_path, {
            "config": {"fc": "ardupilot", "seed": seed, "plan": run.name,
                       "physics_hz": phys.physics_hz, "sitl_speedup": speed},
            "scenario": sc.to_dict(), "params": defaults, "software": {"arducopter": binary}})
        phys.sink = switching.sink(parts.sink)
        parts.server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(ap.instance)))
        ap.launch(sitl.start_sitl, binary, ap.instance, ap.workdir, speedup=speed,
                  home=sc.home, defaults_path=defaults_path)
        return phys, lambda: TcpLink(port, alive=lambda: not ap.exited()), None

    return switching.done(_as_failure_flight(fly_foreign(
        run, ap, sc, start, stop=stop, connect_timeout_s=60.0,
        client_cls=_client_cls(run, switching.on_client), fly=fly_failure)))


def fly_px4(run: PlanRun, *, seed: int, log_path: str, speed: float, binary: str,
            stop=None) -> FailureFlight:
    from silbridge.bridge.autopilots.px4.hil_messages import SIM_COMPID, SIM_SYSID
    from silbridge.bridge.autopilots.px4.physics import Px4Physics
    from silbridge.bridge.autopilots.px4.server import Px4HilServer
    from silbridge.mavlink.hil.hil_channel import make_codec
    from silbridge.tools.autopilots.common.run import AutopilotRun, scenario_factory
    from silbridge.tools.autopilots.px4 import sitl
    from silbridge.tools.benchmark.nav.in_process import GroundTruthLog, fly_foreign
    from silbridge.tools.benchmark.nav.run_px4 import _offboard_link
    from silbridge.tools.benchmark.nav.ways import Px4Ways

    binary, etc = sitl.require_px4(binary)
    sc, make_sim = scenario_factory(run.physics_path, seed, None)
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    p4 = sitl.px4_params(phys.sim, sc, overrides={**fs.PX4, **boot_params("px4", phys.sim)})
    ap = AutopilotRun(sitl.PX4, "silbridge-failures-px4-")
    switching = _Switching("px4", run, sc.home.lat_deg)

    def start(parts):
        parts.sink = GroundTruthLog(log_path, {
            "config": {"fc": "px4", "seed": seed, "plan": run.name,
                       "physics_hz": phys.sim.physics_hz},
            "scenario": sc.to_dict(), "params": p4, "software": {"px4": binary}})
        phys.sink = switching.sink(parts.sink)
        parts.server = Px4HilServer(phys, ("127.0.0.1", sitl.SIM_TCP_BASE + ap.instance))
        ap.launch(sitl.start_px4, binary, etc, ap.instance, ap.workdir, params=p4)
        return phys, lambda: _offboard_link(ap.instance), Px4Ways()

    return switching.done(_as_failure_flight(fly_foreign(
        run, ap, sc, start, stop=stop, connect_timeout_s=30.0,
        client_cls=_client_cls(run, switching.on_client), fly=fly_failure)))


RUNNERS = {"ours": fly_ours, "ardupilot": fly_ardupilot, "px4": fly_px4}
