"""Flights with PX4 SITL as the flight controller over MAVLink HIL, wired from their parts.

`serve_px4`: `silbridge bridge --fc px4`: our physics for a PX4 the user started
(`PX4_SYS_AUTOSTART=10016 px4 -i N`), lockstep or real time; they fly it from their own GCS
(QGroundControl on UDP 14550).
`fly_px4`: one run of `silbridge bench --fc px4`: a fresh PX4 per run in its own working
directory and instance (tools/autopilots/sitl_px4.py), our physics on its simulator link
(bridge/px4_physics.py, bridge/px4_server.py), flown over its offboard link (tools/autopilots/px4_driver.py:
arm, take off, OFFBOARD), the scenario's setpoints as attitude targets
(tools/autopilots/px4_setpoints.py), logged from the bridge side exactly as ArduCopter runs are
(tools/autopilots/ardupilot_log.py: /fc/status att_target_rad = the command sent, ap_target_rad = PX4's
own ATTITUDE_TARGET), so tools/benchmark/metrics.py computes the same Table 1 metrics.
A PX4 whose height at rest never settles (tools/autopilots/px4_rest_height.py) is never
flown: it is stopped and a fresh one booted, as a user power-cycles a vehicle whose ground
station shows it off the ground, at most HEIGHT_RESTARTS times (`px4_restarts` in the
summary).
"""

from __future__ import annotations

import math

from silbridge.bridge.px4_physics import Px4Physics
from silbridge.bridge.px4_server import Px4HilServer
from silbridge.mavlink.hil.hil_channel import make_codec

from silbridge.tools.autopilots.ardupilot_flight import BenchStepHooks
from silbridge.tools.autopilots.ardupilot_log import ArduPilotLogSink, AttitudeTarget
from silbridge.tools.autopilots.autopilot_run import (
    AutopilotRun,
    flight_summary,
    flight_metadata,
    run_summary,
    scenario_factory,
)
from silbridge.tools.logs.fc_target import TargetFeed
from silbridge.tools.autopilots.px4_driver import Px4Driver
from silbridge.tools.autopilots.px4_setpoints import Px4SetpointForwarder
from silbridge.tools.autopilots.sitl_px4 import (
    PX4,
    SIM_TCP_BASE,
    Px4Error,
    px4_params,
    start_px4,
)

_NS = 1_000_000_000
BOOT_BUDGET_S = 90.0     # sim seconds PX4 may take from boot to an accepted take-off
SIM_SYSID, SIM_COMPID = 1, 51
HEIGHT_RESTARTS = 3      # fresh PX4 boots after one whose height at rest did not settle


class HeightUnsettled(Px4Error):
    """PX4's height at rest did not settle before take-off (the run is restarted)."""


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


def fly_px4(**kw) -> dict:
    """One PX4 run: boot, arm, take off, OFFBOARD for duration_s; log from take-off (the
    arguments of `_fly_once`). A boot whose height at rest does not settle is restarted."""
    for restarts in range(HEIGHT_RESTARTS + 1):
        try:
            summary = _fly_once(**kw)
        except HeightUnsettled as e:
            why = str(e)
            continue
        summary["px4_restarts"] = restarts
        return summary
    raise HeightUnsettled(f"{why}, in {HEIGHT_RESTARTS + 1} boots of PX4 in a row: is the "
                          "machine overloaded? (lockstep, the default, has not shown it)")


def _fly_once(*, scenario: str, seed, duration_s: float, log_path: str, binary: str, etc: str,
              imu_hz=None, params: dict | None = None, realtime: bool = False,
              boot_budget_s: float = BOOT_BUDGET_S, keep_dir: bool = False,
              spin_us: float = 0.0) -> dict:
    """spin_us: the lockstep link's spin budget (bridge/link_spin.py; campaigns choose it)."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    target = AttitudeTarget()
    feed = TargetFeed()
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    sim = phys.sim
    p4 = px4_params(sim, sc, overrides=params)
    run = AutopilotRun(PX4, "silbridge-px4-", keep_dir=keep_dir)
    driver = server = sink = None
    try:
        driver = Px4Driver(run.instance, sim_time_s=lambda: phys.sim.sim_ns / _NS,
                           target=target, on_takeoff=lambda: hooks.takeoff_accepted(),
                           on_takeoff_sent=lambda: hooks.takeoff_sent(phys.sim.sim_ns),
                           target_feed=feed, sim_ns=lambda: phys.sim.sim_ns)
        forwarder = Px4SetpointForwarder(sc, sim.dt_ns, math.radians(sc.home.heading_deg),
                                         send=driver.send_attitude_target, driver=driver,
                                         hover_thrust=p4["MPC_THR_HOVER"])
        sink = ArduPilotLogSink(log_path, target=target, duration_s=duration_s,
                                command=forwarder, target_feed=feed,
                                metadata=_metadata(sc, phys, duration_s, p4, binary, realtime))
        hooks = phys.sink = BenchStepHooks(forwarder, sink)
        server = Px4HilServer(phys, ("127.0.0.1", SIM_TCP_BASE + run.instance))
        run.launch(start_px4, binary, etc, run.instance, run.workdir, params=p4)
        driver.start()
        res = server.serve(boot_budget_s + duration_s, realtime=realtime,
                           stop=run.stop_when(
                               lambda: sink.done or driver.height_unsettled is not None, driver),
                           connect_timeout_s=30.0, spin_us=spin_us)
        if driver.height_unsettled is not None:
            raise HeightUnsettled(driver.height_unsettled)
        run.raise_if_failed(sink, driver, boot_budget_s,
                            mode=f"{driver.main_mode}/{driver.sub_mode}")
    finally:
        run.close(driver, server)
        if sink is not None:
            sink.close(fc="px4", takeoff_physics_ns=sink.t0_ns, px4_instance=run.instance,
                       **forwarder.summary())
    return flight_summary("px4", sc, res, run, sink, log_path,
                          link={"hil_link": res.stats, "startup_check": res.startup_check},
                          imu_hz=phys.sim.imu_hz, **_offboard(driver, sink),
                          rest_height=driver.rest_height.summary(), **forwarder.summary())


def _offboard(driver, sink) -> dict:
    """PX4's OFFBOARD mode over the flight: `offboard` at the end, `offboard_from_s` the
    flight time (from the take-off command) of the first heartbeat in it and
    `offboard_left_s` of the first one out of it after that (None: never)."""
    t0 = sink.t0_ns / _NS

    def flight_s(t):
        return None if t is None else round(t - t0, 3)

    return {"offboard": driver.offboard, "offboard_from_s": flight_s(driver.offboard_since_s),
            "offboard_left_s": flight_s(driver.offboard_left_s)}


def _metadata(sc, phys, duration_s, params, binary, realtime) -> dict:
    return flight_metadata(
        sc, phys.sim, fc="px4", physics_hz=phys.sim.physics_hz, duration_s=duration_s,
        transport="px4-mavlink-hil", mode="realtime" if realtime else "lockstep",
        params=params, software={"px4": binary},
        # PX4 answers once per PX4 step (px4_step_hz); /pwm and /fc/status hold one row
        # per physics step (its outputs held), as ArduCopter runs do.
        px4_step_hz=phys.step_hz,
        att_target="scenario command sent to PX4 (SET_ATTITUDE_TARGET, OFFBOARD)",
        fc_target="PX4's ATTITUDE_TARGET in /fc/target (and /fc/status ap_target_rad)",
        timing="PX4 HIL link, bridge side: imu_wall_ns = HIL_ACTUATOR_CONTROLS "
               "arrival, consume_wall_ns = physics step done, pwm_wall_ns = sensors sent")
