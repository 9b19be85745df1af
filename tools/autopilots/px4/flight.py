"""Flights with PX4 SITL as the flight controller over MAVLink HIL, wired from their parts.

`fly_px4`: one run of `silbridge bench --fc px4`: a fresh PX4 per run in its own working
directory and instance (tools/autopilots/px4/sitl.py), our physics on its simulator link
(bridge/autopilots/px4/physics.py, server.py), flown over its offboard link
(tools/autopilots/px4/driver.py: arm, take off, OFFBOARD), the scenario's setpoints as
attitude targets (tools/autopilots/px4/setpoints.py), logged from the bridge side exactly as
ArduCopter runs are and wired the same way (tools/autopilots/common/log_sink.py, flight.py:
/fc/status att_target_rad = the command sent, ap_target_rad = PX4's own ATTITUDE_TARGET),
so tools/benchmark/metrics.py computes the same Table 1 metrics.
A PX4 whose height at rest never settles (tools/autopilots/px4/rest_height.py) is never
flown: it is stopped and a fresh one booted, as a user power-cycles a vehicle whose ground
station shows it off the ground, at most HEIGHT_RESTARTS times (`px4_restarts` in the
summary).
"""

from __future__ import annotations

import math

from silbridge.bridge.autopilots.px4.hil_messages import SIM_COMPID, SIM_SYSID
from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.autopilots.px4.server import Px4HilServer
from silbridge.mavlink.hil.hil_channel import make_codec

from silbridge.tools.autopilots.common.flight import BenchWiring
from silbridge.tools.autopilots.common.run import (AutopilotRun, flight_metadata, flight_summary,
                                                   scenario_factory)
from silbridge.tools.autopilots.px4.driver import Px4Driver
from silbridge.tools.autopilots.px4.setpoints import Px4SetpointForwarder
from silbridge.tools.autopilots.px4.sitl import PX4, SIM_TCP_BASE, Px4Error, px4_params, start_px4
from silbridge.shm.records import NS_PER_S as _NS

BOOT_BUDGET_S = 90.0     # sim seconds PX4 may take from boot to an accepted take-off
HEIGHT_RESTARTS = 3      # fresh PX4 boots after one whose height at rest did not settle


class HeightUnsettled(Px4Error):
    """PX4's height at rest did not settle before take-off (the run is restarted)."""


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
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    wiring = BenchWiring(phys)
    p4 = px4_params(phys.sim, sc, overrides=params)
    run = AutopilotRun(PX4, "silbridge-px4-", keep_dir=keep_dir)
    driver = server = None
    try:
        driver = Px4Driver(run.instance, **wiring.driver_reports())
        forwarder = Px4SetpointForwarder(sc, phys.sim.dt_ns, math.radians(sc.home.heading_deg),
                                         send=driver.send_attitude_target, driver=driver,
                                         hover_thrust=p4["MPC_THR_HOVER"])
        sink = wiring.log(log_path, forwarder=forwarder, duration_s=duration_s,
                          metadata=_metadata(sc, phys, duration_s, p4, binary, realtime))
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
        wiring.close_log("px4", px4_instance=run.instance)
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
