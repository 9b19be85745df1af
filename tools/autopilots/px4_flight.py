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
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time

from silbridge.bridge.px4_physics import Px4Physics
from silbridge.bridge.px4_server import Px4HilServer
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_channel import make_codec

from silbridge.tools.autopilots.ardupilot_flight import BenchStepHooks
from silbridge.tools.autopilots.ardupilot_log import ArduPilotLogSink, AttitudeTarget
from silbridge.tools.logs.fc_target import TargetFeed
from silbridge.tools.autopilots.px4_driver import Px4Driver
from silbridge.tools.autopilots.px4_setpoints import Px4SetpointForwarder
from silbridge.tools.autopilots.sitl_px4 import (
    SIM_TCP_BASE,
    Px4Error,
    log_tail,
    pick_instance,
    px4_params,
    release_instance,
    start_px4,
    stop_px4,
)

_NS = 1_000_000_000
BOOT_BUDGET_S = 90.0     # sim seconds PX4 may take from boot to an accepted take-off
SIM_SYSID, SIM_COMPID = 1, 51


def _factory(scenario: str, seed, imu_hz):
    sc = load_scenario(scenario, seed=seed)
    return sc, (lambda: Simulator(sc, imu_hz=imu_hz))


def _summary(sc, phys, res, **extra) -> dict:
    return {"fc": "px4", "scenario": sc.name, "seed": sc.seed, "sim_s": res.sim_s,
            "wall_s": res.wall_s, "realtime_factor": res.sim_s / max(res.wall_s, 1e-9),
            "crashed": res.crashed, "crash_reason": res.crash_reason,
            "stopped_by": res.stopped_by, "hil_link": res.stats,
            "startup_check": res.startup_check, "imu_hz": phys.sim.imu_hz, **extra}


def serve_px4(scenario: str, *, seed=None, imu_hz=None, duration_s=None, realtime=False,
              address=("127.0.0.1", SIM_TCP_BASE), channel=None, out=print) -> dict:
    """Our physics on PX4's simulator link until the scenario's duration of sim time."""
    sc, make_sim = _factory(scenario, seed, imu_hz)
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    with Px4HilServer(phys, address, channel=channel) as server:
        where = (f"tcp {server.address[0]}:{server.address[1]}" if channel is None
                 else channel.name)
        n = server.address[1] - SIM_TCP_BASE if channel is None else 0
        out(f"bridge: PX4 simulator link on {where} ({'real time' if realtime else 'lockstep'}); "
            f"start `PX4_SYS_AUTOSTART=10016 px4 -i {n}` (PX4 v1.15, airframe none_iris)")
        res = server.serve(duration_s if duration_s is not None else sc.duration_s,
                           realtime=realtime, connect_timeout_s=600.0)
    return _summary(sc, phys, res)


def fly_px4(*, scenario: str, seed, duration_s: float, log_path: str, binary: str, etc: str,
            imu_hz=None, params: dict | None = None, realtime: bool = False,
            boot_budget_s: float = BOOT_BUDGET_S, keep_dir: bool = False) -> dict:
    """One PX4 run: boot, arm, take off, OFFBOARD for duration_s; log from take-off."""
    sc, make_sim = _factory(scenario, seed, imu_hz)
    target = AttitudeTarget()
    feed = TargetFeed()
    phys = Px4Physics(make_sim, make_codec(SIM_SYSID, SIM_COMPID))
    sim = phys.sim
    p4 = px4_params(sim, sc, overrides=params)
    instance = pick_instance()
    workdir = tempfile.mkdtemp(prefix="silbridge-px4-")
    try:
        driver = Px4Driver(instance, sim_time_s=lambda: phys.sim.sim_ns / _NS, target=target,
                           on_takeoff=lambda: hooks.takeoff_accepted(),
                           on_takeoff_sent=lambda: hooks.takeoff_sent(phys.sim.sim_ns),
                           target_feed=feed, sim_ns=lambda: phys.sim.sim_ns)
    except BaseException:
        release_instance(instance)
        shutil.rmtree(workdir, ignore_errors=True)
        raise
    forwarder = Px4SetpointForwarder(sc, sim.dt_ns, math.radians(sc.home.heading_deg),
                                     send=driver.send_attitude_target, driver=driver,
                                     hover_thrust=p4["MPC_THR_HOVER"])
    sink = ArduPilotLogSink(log_path, metadata=_metadata(sc, sim, phys, duration_s, p4, binary,
                                                         realtime),
                            target=target, duration_s=duration_s, command=forwarder,
                            target_feed=feed)
    hooks = phys.sink = BenchStepHooks(forwarder, sink)
    proc = None
    server = None
    t0 = time.monotonic()
    res = None
    try:
        server = Px4HilServer(phys, ("127.0.0.1", SIM_TCP_BASE + instance))
        proc = start_px4(binary, etc, instance, workdir, params=p4)
        driver.start()

        def stop() -> bool:
            return sink.done or proc.poll() is not None or driver.error is not None

        res = server.serve(boot_budget_s + duration_s, realtime=realtime, stop=stop,
                           connect_timeout_s=30.0)
        _raise_if_failed(sink, proc, driver, workdir, boot_budget_s)
    finally:
        if driver.is_alive():
            driver.stop()
        else:
            driver.sock.close()
        if proc is not None:
            stop_px4(proc, instance)
        if server is not None:
            server.close()
        release_instance(instance)
        sink.close(fc="px4", takeoff_physics_ns=sink.t0_ns, px4_instance=instance,
                   **forwarder.summary())
        if not keep_dir:
            shutil.rmtree(workdir, ignore_errors=True)
    flight_s = (sink.last_sim_ns - sink.t0_ns) / _NS
    return _summary(sc, phys, res, flight_sim_s=flight_s, sim_s_total=res.sim_s,
                    takeoff_physics_s=sink.t0_ns / _NS, log=log_path,
                    wall_total_s=time.monotonic() - t0, offboard=driver.offboard,
                    **forwarder.summary()) | {"sim_s": flight_s}


def _raise_if_failed(sink, proc, driver, workdir, boot_budget_s) -> None:
    said = "; PX4 said: " + " | ".join(driver.statustext) if driver.statustext else ""
    if driver.error is not None:
        raise Px4Error(f"MAVLink to PX4 SITL failed: {driver.error}{said}")
    if sink.t0_ns is None:
        if proc.poll() is not None:
            raise Px4Error(f"PX4 SITL exited with status {proc.returncode} before take-off; "
                           f"its output: {log_tail(workdir)}")
        raise Px4Error(f"PX4 did not take off within {boot_budget_s:g} s of sim time "
                       f"(armed={driver.armed}, mode={driver.main_mode}/{driver.sub_mode})"
                       f"{said}")
    if not sink.done and proc.poll() is not None:
        raise Px4Error(f"PX4 SITL exited with status {proc.returncode} in flight; its output: "
                       f"{log_tail(workdir)}")


def _metadata(sc, sim, phys, duration_s, params, binary, realtime) -> dict:
    from silbridge.tools.loop.flight import _version
    return {
        "config": {
            "imu_hz": sim.imu_hz, "pwm_hz": sim.physics_hz, "physics_hz": sim.physics_hz,
            "baro_hz": sc.baro_hz, "mag_hz": sc.mag_hz, "gnss_hz": sc.gnss_hz,
            "duration_s": duration_s, "seed": sc.seed, "transport": "px4-mavlink-hil",
            "processes": 2, "mode": "realtime" if realtime else "lockstep",
            "features_off": [], "fc": "px4",
            # PX4 answers once per PX4 step (px4_step_hz); /pwm and /fc/status hold one row
            # per physics step (its outputs held), as ArduCopter runs do.
            "px4_step_hz": phys.step_hz,
            "att_target": "scenario command sent to PX4 (SET_ATTITUDE_TARGET, OFFBOARD)",
            "fc_target": "PX4's ATTITUDE_TARGET in /fc/target (and /fc/status ap_target_rad)",
            "timing": "PX4 HIL link, bridge side: imu_wall_ns = HIL_ACTUATOR_CONTROLS "
                      "arrival, consume_wall_ns = physics step done, pwm_wall_ns = sensors "
                      "sent",
        },
        "scenario": sc.to_dict(),
        "params": dict(params),
        "software": {"silbridge": _version(), "px4": binary},
    }
