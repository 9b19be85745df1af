"""A foreign autopilot's run on our physics (ArduCopter or PX4 SITL): what every run shares.

    run = AutopilotRun(ARDUCOPTER, "silbridge-sitl-", keep_dir=False)   # dir + free instance
    try:
        run.launch(start_sitl, binary, run.instance, run.workdir, ...)
        res = server.serve(..., stop=run.stop_when(lambda: sink.done, driver))
        run.raise_if_failed(sink, driver, boot_budget_s, mode=...)
    finally:
        run.close(driver, server)        # on every exit path

Each autopilot's own `sitl.py` describes it once as an `Autopilot` (process.py). A run owns a fresh
working directory (removed at the end unless kept) and a free instance, and `close` ends the
run in one order whatever happened: the MAVLink driver, the autopilot's process, our server,
the instance's claim, the directory. The flights' summaries and log metadata share their
keys and their order here, so ArduCopter and PX4 rows read alike (`run_summary`,
`flight_summary`, `flight_metadata`, and `report_summary` for `silbridge bridge --fc X`).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import time
from contextlib import ExitStack
from typing import Callable

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator

from silbridge.tools.autopilots.common.process import Autopilot, log_tail
from silbridge.shm.records import NS_PER_S as _NS


def scenario_factory(scenario: str, seed, imu_hz):
    """(the scenario, a maker of its simulator): the physics wrappers build the simulator."""
    sc = load_scenario(scenario, seed=seed)
    if sc.fc_params:
        # [[fc_param]] names our FC's parameters; an autopilot has its own.
        raise ScenarioError(f"scenario {sc.name}: its [[fc_param]] entries set silbridge's FC "
                            "parameters, which ArduCopter and PX4 do not have; fly it with "
                            "--fc ours, or use a scenario without [[fc_param]]")
    return sc, (lambda: Simulator(sc, imu_hz=imu_hz))


def _end_driver(driver) -> None:
    # A driver thread closes its own socket when it ends; one that never ran (or a run
    # that failed before starting it) still holds the socket it bound.
    if driver.is_alive():
        driver.stop()
    elif getattr(driver, "sock", None) is not None:
        driver.sock.close()


class AutopilotRun:
    """One run: a fresh working directory, a free instance, the process, ended by close()."""

    def __init__(self, autopilot: Autopilot, prefix: str, *, keep_dir: bool = False):
        self.autopilot = autopilot
        self.keep_dir = keep_dir
        self.workdir = tempfile.mkdtemp(prefix=prefix)
        try:
            self.instance = autopilot.pick()
        except BaseException:
            shutil.rmtree(self.workdir, ignore_errors=True)
            raise
        self.proc: subprocess.Popen | None = None
        self.t0 = time.monotonic()
        self.tail = ""           # the console log's last lines, kept by close()

    def launch(self, start, *args, **kwargs) -> subprocess.Popen:
        """start(*args, **kwargs) -> the autopilot's process; the run's wall clock starts."""
        self.t0 = time.monotonic()
        self.proc = start(*args, **kwargs)
        return self.proc

    def exited(self) -> bool:
        return self.proc is not None and self.proc.poll() is not None

    def stop_when(self, done: Callable[[], bool], driver=None) -> Callable[[], bool]:
        """A server's stop(): done() says so, the autopilot exited, or its driver failed."""
        return lambda: done() or self.exited() or (driver is not None
                                                   and driver.error is not None)

    def log_tail(self) -> str:
        return log_tail(os.path.join(self.workdir, self.autopilot.log_name))

    def raise_if_failed(self, sink, driver, boot_budget_s: float, *, mode: str) -> None:
        """The autopilot's error when the flight did not happen; mode: its mode, as text."""
        name, error = self.autopilot.name, self.autopilot.error
        said = f"; {name} said: " + " | ".join(driver.statustext) if driver.statustext else ""
        if driver.error is not None:
            raise error(f"MAVLink to {name} SITL failed: {driver.error}{said}")
        if sink.t0_ns is None:
            if self.exited():
                raise error(f"{name} SITL exited with status {self.proc.returncode} before "
                            f"take-off; its output: {self.log_tail()}")
            raise error(f"{name} did not take off within {boot_budget_s:g} s of sim time "
                        f"(armed={driver.armed}, mode={mode}){said}")
        if not sink.done and self.exited():
            raise error(f"{name} SITL exited with status {self.proc.returncode} in flight; "
                        f"its output: {self.log_tail()}")

    def close(self, driver=None, server=None) -> None:
        """End the run, in this order, each step even when one before it failed: the
        driver, the autopilot's process, the server, the instance, the directory."""
        with ExitStack() as steps:                     # runs its callbacks last-in first
            steps.callback(self._remove_dir)
            steps.callback(self.autopilot.release, self.instance)
            if server is not None:
                steps.callback(server.close)
            if self.proc is not None:
                steps.callback(self.autopilot.stop, self.proc, self.instance)
            if driver is not None:
                steps.callback(_end_driver, driver)

    def _remove_dir(self) -> None:
        self.tail = self.log_tail()
        if not self.keep_dir:
            shutil.rmtree(self.workdir, ignore_errors=True)


def run_summary(fc: str, sc, res, *, link: dict, imu_hz, **extra) -> dict:
    """A run's summary: the same keys, in the same order, for every autopilot.
    link: the link's counters under its own key(s), e.g. {"json_link": res.stats}."""
    return {"fc": fc, "scenario": sc.name, "seed": sc.seed, "sim_s": res.sim_s,
            "wall_s": res.wall_s, "realtime_factor": res.sim_s / max(res.wall_s, 1e-9),
            "crashed": res.crashed, "crash_reason": res.crash_reason,
            "stopped_by": res.stopped_by, **link, "imu_hz": imu_hz, **extra}


def flight_summary(fc: str, sc, res, run: AutopilotRun, sink, log_path: str, *, link: dict,
                   imu_hz, **extra) -> dict:
    """A bench flight's summary: sim_s is the logged flight (from the take-off), sim_s_total
    and wall_total_s the whole run, boot included."""
    flight_s = (sink.last_sim_ns - sink.t0_ns) / _NS
    return run_summary(fc, sc, res, link=link, imu_hz=imu_hz, flight_sim_s=flight_s,
                       sim_s_total=res.sim_s, takeoff_physics_s=sink.t0_ns / _NS, log=log_path,
                       wall_total_s=time.monotonic() - run.t0, **extra) | {"sim_s": flight_s}


def flight_metadata(sc, sim, *, fc: str, physics_hz: float, duration_s: float, transport: str,
                 mode: str, params: dict, software: dict, **config) -> dict:
    """A bench flight's log metadata; config: the autopilot's own entries, after the shared."""
    from silbridge.tools.version import package_version
    return {
        "config": {
            "imu_hz": sim.imu_hz, "pwm_hz": physics_hz, "physics_hz": physics_hz,
            "rotor_hz": physics_hz,     # /rotor, written per step by the log sink
            "baro_hz": sc.baro_hz, "mag_hz": sc.mag_hz, "gnss_hz": sc.gnss_hz,
            "duration_s": duration_s, "seed": sc.seed, "transport": transport,
            "processes": 2, "mode": mode, "features_off": [], "fc": fc, **config,
        },
        "scenario": sc.to_dict(),
        "params": dict(params),
        "software": {"silbridge": package_version(), **software},
    }


def report_summary(summary: dict, *, as_json: bool, out, line) -> int:
    """The end of `silbridge bridge --fc X`: the summary as one JSON object on stdout, or
    line(summary) to `out`; exit status 1 when the vehicle crashed."""
    if as_json:
        print(json.dumps(summary))
    else:
        out(line(summary))
    return 1 if summary["crashed"] else 0
