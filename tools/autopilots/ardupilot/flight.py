"""Flights with ArduCopter SITL as the flight controller, wired from their parts.

`fly_ardupilot`: one benchmark run of `silbridge bench --fc ardupilot`: a
fresh SITL per run (tools/autopilots/ardupilot/sitl.py), driven over MAVLink
(tools/autopilots/ardupilot/driver.py: GUIDED, arm, take off), the scenario's setpoints
forwarded to it from take-off on (tools/autopilots/ardupilot/setpoints.py), logged from the
bridge side (tools/autopilots/common/log_sink.py: records, PWM, commanded attitude, JSON-link
timing; wired as for PX4 by tools/autopilots/common/flight.py) so tools/benchmark/metrics.py
computes the same Table 1 metrics, latency and jitter included, as for our FC.
"""

from __future__ import annotations

import math
import os

from silbridge.bridge.autopilots.ardupilot.json_protocol import sitl_port
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer

from silbridge.tools.autopilots.ardupilot.driver import MavlinkDriver
from silbridge.tools.autopilots.ardupilot.setpoints import ArduCopterSetpointForwarder
from silbridge.tools.autopilots.ardupilot.sitl import (ARDUCOPTER, sitl_defaults, start_sitl,
                                                       write_defaults)
from silbridge.tools.autopilots.common.flight import BenchWiring
from silbridge.tools.autopilots.common.run import (AutopilotRun, flight_metadata, flight_summary,
                                                   scenario_factory)

BOOT_BUDGET_S = 120.0   # sim seconds SITL may take from boot to an accepted take-off


def fly_ardupilot(*, scenario: str, seed, duration_s: float, log_path: str, binary: str,
                  imu_hz=None, params: dict | None = None, speedup: float = 50.0,
                  boot_budget_s: float = BOOT_BUDGET_S, keep_dir: bool = False,
                  spin_us: float = 0.0) -> dict:
    """One ArduCopter run: boot, arm, take off, hold for duration_s; log from take-off.
    spin_us: the JSON link's spin budget (bridge/link_spin.py; campaigns choose it)."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    run = AutopilotRun(ARDUCOPTER, "silbridge-sitl-", keep_dir=keep_dir)
    driver = server = wiring = None
    try:
        notes = []
        phys = ArduPilotPhysics(make_sim, note=notes.append)
        wiring = BenchWiring(phys)
        defaults = sitl_defaults(phys.sim, phys.physics_hz, params)
        defaults_path = os.path.join(run.workdir, "silbridge-defaults.parm")
        write_defaults(defaults_path, defaults)
        driver = MavlinkDriver(run.instance, takeoff_alt_m=sc.takeoff_alt_m,
                               **wiring.driver_reports())
        forwarder = ArduCopterSetpointForwarder(sc, phys.sim.dt_ns,
                                                math.radians(sc.home.heading_deg),
                                                send=driver.send_attitude_target,
                                                reported_alt_m=driver.reported_alt_m)
        sink = wiring.log(log_path, forwarder=forwarder, duration_s=duration_s,
                          metadata=_metadata(sc, phys, duration_s, defaults, binary, speedup))
        server = JsonPhysicsServer(phys, ("127.0.0.1", sitl_port(run.instance)))
        run.launch(start_sitl, binary, run.instance, run.workdir, speedup=speedup,
                   home=sc.home, defaults_path=defaults_path)
        driver.start()
        res = server.serve(boot_budget_s + duration_s,
                           stop=run.stop_when(lambda: sink.done, driver), connect_timeout_s=60.0,
                           spin_us=spin_us)
        run.raise_if_failed(sink, driver, boot_budget_s, mode=f"{driver.mode}")
    finally:
        run.close(driver, server)
        if wiring is not None:
            wiring.close_log("ardupilot", notes=notes)
    return flight_summary("ardupilot", sc, res, run, sink, log_path,
                          link={"json_link": res.stats}, imu_hz=phys.sim.imu_hz,
                          **forwarder.summary())


def _metadata(sc, phys, duration_s, defaults, binary, speedup) -> dict:
    return flight_metadata(
        sc, phys.sim, fc="ardupilot", physics_hz=phys.physics_hz, duration_s=duration_s,
        transport="ardupilot-json", mode="lockstep", params=defaults,
        software={"arducopter": binary}, sitl_speedup=speedup,
        # What the channels mean in this log (tools/autopilots/common/log_sink.py, docs/logs.md).
        att_target="scenario command sent to ArduCopter (SET_ATTITUDE_TARGET)",
        command="/setpoint: the command forwarded, on the log clock",
        fc_target="/fc/target: ArduCopter's ATTITUDE_TARGET, stamped time_boot_ms",
        timing="JSON link, bridge side: imu_wall_ns = servo packet arrival, "
               "consume_wall_ns = physics step done, pwm_wall_ns = reply sent")
