"""Flights with ArduCopter SITL as the flight controller, wired from their parts.

`serve_bridge`: `silbridge bridge --fc ardupilot`: our physics on SITL's JSON
port for a SITL the user started (and flies from their own GCS).
`fly_ardupilot`: one benchmark run of `silbridge bench --fc ardupilot`: a
fresh SITL per run, driven over MAVLink (tools/autopilots/sitl_ardupilot.py: GUIDED, arm,
take off), the scenario's setpoints forwarded to it from take-off on
(tools/autopilots/ardupilot_setpoints.py), logged from the bridge side
(tools/autopilots/ardupilot_log.py: records, PWM, commanded attitude, JSON-link timing)
so tools/benchmark/metrics.py computes the same Table 1 metrics, latency and jitter
included, as for our FC.
"""

from __future__ import annotations

import math
import os

from silbridge.bridge.ardupilot_json import sitl_port
from silbridge.bridge.ardupilot_physics import ArduPilotPhysics
from silbridge.bridge.ardupilot_server import JsonPhysicsServer, parse_address

from silbridge.tools.autopilots.ardupilot_log import ArduPilotLogSink, AttitudeTarget
from silbridge.tools.autopilots.ardupilot_setpoints import SetpointForwarder
from silbridge.tools.autopilots.autopilot_run import (
    AutopilotRun,
    flight_summary,
    flight_metadata,
    run_summary,
    scenario_factory,
)
from silbridge.tools.logs.fc_target import TargetFeed
from silbridge.tools.autopilots.sitl_ardupilot import (
    ARDUCOPTER,
    MavlinkDriver,
    sitl_defaults,
    start_sitl,
    write_defaults,
)

_NS = 1_000_000_000
BOOT_BUDGET_S = 120.0   # sim seconds SITL may take from boot to an accepted take-off


class BenchStepHooks:
    """The physics' sink during a bench run: the take-off hand-over, then per step forward the
    setpoints and log.

    The MAVLink thread only records what happened (`takeoff_sent`: the physics time a
    MAV_CMD_NAV_TAKEOFF was written; `takeoff_accepted`: its ACK arrived); the physics
    thread acts on it at its next step, so the log and the forwarder are touched by one
    thread only, and both take the accepted command's send time as their time 0.
    """

    def __init__(self, forwarder: SetpointForwarder, log: ArduPilotLogSink):
        self.forwarder = forwarder
        self.log = log
        self.timing = log.timing
        self._sent_ns: int | None = None     # written by the MAVLink thread
        self._accepted = False               # written by the MAVLink thread
        self._pending_ns: int | None = None

    def takeoff_sent(self, sim_ns: int) -> None:
        self._sent_ns = int(sim_ns)

    def takeoff_accepted(self) -> None:
        self._accepted = True

    def step(self, recs, pwm, sim) -> None:
        log = self.log
        if log.t0_ns is None:
            sent = self._sent_ns
            if sent is not None and sent != self._pending_ns:
                self._pending_ns = sent
                log.pending_from(sent)
            if self._accepted and self._pending_ns is not None:
                self.forwarder.start_at(self._pending_ns)
                log.start_at(self._pending_ns)
        # Before the log writes the step, so its status row holds the command just sent.
        self.forwarder.step(int(pwm["sim_ns"][0]))
        log.step(recs, pwm, sim)


def serve_bridge(scenario: str, *, seed=None, imu_hz=None, duration_s=None,
                 sitl_address: str | None = None, out=print) -> dict:
    """Answer one SITL's servo packets until the scenario's duration of sim time."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    phys = ArduPilotPhysics(make_sim, note=lambda t: out(f"bridge: {t}"))
    address = parse_address(sitl_address, sitl_port(0))
    with JsonPhysicsServer(phys, address) as server:
        host, port = server.address
        n, off = divmod(port - 9002, 10)
        inst = f" --instance {n}" if n >= 0 and off == 0 else ""
        out(f"bridge: ArduPilot JSON physics on udp {host}:{port}; start "
            f"`arducopter --model JSON:{host}{inst}` with SIM_RATE_HZ {phys.physics_hz:g}, "
            "FRAME_CLASS 1, FRAME_TYPE 1")
        res = server.serve(duration_s if duration_s is not None else sc.duration_s)
    return run_summary("ardupilot", sc, res, link={"json_link": res.stats},
                       imu_hz=phys.sim.imu_hz)


def fly_ardupilot(*, scenario: str, seed, duration_s: float, log_path: str, binary: str,
                  imu_hz=None, params: dict | None = None, speedup: float = 50.0,
                  boot_budget_s: float = BOOT_BUDGET_S, keep_dir: bool = False,
                  spin_us: float = 0.0) -> dict:
    """One ArduCopter run: boot, arm, take off, hold for duration_s; log from take-off.
    spin_us: the JSON link's spin budget (bridge/link_spin.py; campaigns choose it)."""
    sc, make_sim = scenario_factory(scenario, seed, imu_hz)
    target = AttitudeTarget()
    feed = TargetFeed()
    run = AutopilotRun(ARDUCOPTER, "silbridge-sitl-", keep_dir=keep_dir)
    driver = server = sink = None
    try:
        notes = []
        phys = ArduPilotPhysics(make_sim, note=notes.append)
        sim = phys.sim
        defaults = sitl_defaults(sim, phys.physics_hz, params)
        defaults_path = os.path.join(run.workdir, "silbridge-defaults.parm")
        write_defaults(defaults_path, defaults)
        driver = MavlinkDriver(run.instance, takeoff_alt_m=sc.takeoff_alt_m,
                               sim_time_s=lambda: phys.sim.sim_ns / _NS,
                               on_takeoff=lambda: hooks.takeoff_accepted(), target=target,
                               on_takeoff_sent=lambda: hooks.takeoff_sent(phys.sim.sim_ns),
                               target_feed=feed, sim_ns=lambda: phys.sim.sim_ns)
        forwarder = SetpointForwarder(sc, sim.dt_ns, math.radians(sc.home.heading_deg),
                                      send=driver.send_attitude_target,
                                      reported_alt_m=driver.reported_alt_m)
        sink = ArduPilotLogSink(log_path, target=target, duration_s=duration_s,
                                command=forwarder, target_feed=feed,
                                metadata=_metadata(sc, phys, duration_s, defaults, binary,
                                                   speedup))
        hooks = phys.sink = BenchStepHooks(forwarder, sink)
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
        if sink is not None:
            sink.close(fc="ardupilot", takeoff_physics_ns=sink.t0_ns, notes=notes,
                       **forwarder.summary())
    return flight_summary("ardupilot", sc, res, run, sink, log_path,
                          link={"json_link": res.stats}, imu_hz=sim.imu_hz,
                          **forwarder.summary())


def _metadata(sc, phys, duration_s, defaults, binary, speedup) -> dict:
    return flight_metadata(
        sc, phys.sim, fc="ardupilot", physics_hz=phys.physics_hz, duration_s=duration_s,
        transport="ardupilot-json", mode="lockstep", params=defaults,
        software={"arducopter": binary}, sitl_speedup=speedup,
        # What the channels mean in this log (tools/autopilots/ardupilot_log.py, docs/logs.md).
        att_target="scenario command sent to ArduCopter (SET_ATTITUDE_TARGET)",
        command="/setpoint: the command forwarded, on the log clock",
        fc_target="/fc/target: ArduCopter's ATTITUDE_TARGET, stamped time_boot_ms",
        timing="JSON link, bridge side: imu_wall_ns = servo packet arrival, "
               "consume_wall_ns = physics step done, pwm_wall_ns = reply sent")
