"""What one run of each `silbridge speed` case is, and how it is measured.

Every run of ours is a fresh interpreter (a subprocess), so no run inherits another's warm
caches or leftover threads, and each is timed by its own figures:
- bare JSBSim: tools/docs/jsbsim_speed.py, one block of `--duration` seconds of `run()` steps;
- our flights: `silbridge fly --json`, whose `realtime_factor` covers the lockstep loop only
  (start-up and the log's closing are outside it, as in every bench figure) and whose
  `loop_cpu_s` is the bridge loop thread's CPU time (with one process: the FC's too);
- ArduCopter: tools/autopilots/ardupilot/speed.py's `measure_reference`, SITL on its own
  physics at `--speedup 1000`, `--duration` sim seconds after the boot's first seconds.

Each run returns {'realtime_factor', 'loop_cpu_s' (None where not measured), 'sim_s'}.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from typing import Callable

from silbridge.tools.loop.flight import last_json_line

SCENARIO = "S1"     # jsbsim_speed's scenario: every case flies or steps the same vehicle
RUN_TIMEOUT_S = 600.0


class SpeedRunError(Exception):
    user_facing = True


@dataclass(frozen=True)
class Case:
    name: str                       # key in the JSON object
    label: str                      # what the table's row says
    run: Callable[[], dict]         # one measured run


def _child(argv: list[str], what: str) -> dict:
    """The JSON object a `python -m ...` child prints; its stderr's tail if it fails."""
    done = subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True,
                          timeout=RUN_TIMEOUT_S)
    out = last_json_line(done.stdout)
    if done.returncode != 0 or not out:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise SpeedRunError(f"{what} failed (exit {done.returncode}: {tail}); run it alone to "
                            f"see why: python -m {' '.join(argv)}")
    return out


def bare_jsbsim(duration_s: float, physics_hz: float) -> Case:
    steps = max(1, round(duration_s * physics_hz))
    argv = ["silbridge.tools.docs.jsbsim_speed", "--steps", str(steps), "--blocks", "1"]

    def run() -> dict:
        r = _child(argv, "bare JSBSim")
        return {"realtime_factor": r["realtime_factor"], "loop_cpu_s": None,
                "sim_s": steps / physics_hz}
    return Case("jsbsim", f"bare JSBSim `run()`, {SCENARIO} at {physics_hz / 1000:g} kHz", run)


def flight(duration_s: float, processes: int, *, log: bool = False,
           imu_hz: int | None = None) -> Case:
    name = f"fly{processes}" + ("_log" if log else "") + (f"_imu{imu_hz}" if imu_hz else "")
    label = f"fly --processes {processes}" + (" --log" if log else "") + \
        (f" --imu-hz {imu_hz}" if imu_hz else "")
    argv = ["silbridge", "fly", "--scenario", SCENARIO, "--processes", str(processes),
            "--duration", f"{duration_s:g}", "--json"]
    if imu_hz:
        argv += ["--imu-hz", str(imu_hz)]

    def run() -> dict:
        with tempfile.TemporaryDirectory(prefix="silbridge-speed-") as tmp:
            log_argv = ["--log", os.path.join(tmp, "run.mcap")] if log else []
            r = _child(argv + log_argv, f"`silbridge {' '.join(argv[1:] + log_argv)}`")
        return {"realtime_factor": r["realtime_factor"], "loop_cpu_s": r["loop_cpu_s"],
                "sim_s": r["sim_s"], "jsbsim_nodes": r.get("jsbsim_nodes")}
    return Case(name, label, run)


def arducopter_own_physics(binary: str, duration_s: float) -> Case:
    from silbridge.tools.docs.results_speed import ARDUCOPTER_SKIP_S

    def run() -> dict:
        from silbridge.tools.autopilots.ardupilot.speed import measure_reference
        r = measure_reference(binary, skip_s=ARDUCOPTER_SKIP_S, span_s=duration_s)
        if not math.isfinite(r["realtime_factor"]):
            # measure_reference gives up after 120 s of wall time without the window's end.
            raise SpeedRunError(f"ArduCopter SITL ({binary}) never reached sim second "
                                f"{ARDUCOPTER_SKIP_S + duration_s:g}: run `python -m "
                                f"silbridge.tools.autopilots.ardupilot.speed` to see why")
        return {"realtime_factor": r["realtime_factor"], "loop_cpu_s": None,
                "sim_s": duration_s}
    return Case("arducopter", "ArduCopter SITL on its own physics (`--model quad`)", run)


def campaign(duration_s: float, jobs: int, runs_per_scenario: int) -> Case:
    """`silbridge bench`'s campaign, S1..S4 x runs_per_scenario, on `jobs` workers: its
    overall factor (all simulated seconds over its wall time) and its runs' median factor."""
    argv = ["silbridge.tools.speed.campaign_run", "--jobs", str(jobs), "--runs",
            str(runs_per_scenario), "--duration", f"{duration_s:g}"]

    def run() -> dict:
        r = _child(argv, f"the campaign on {jobs} job(s)")
        return {"realtime_factor": r["realtime_factor"], "loop_cpu_s": None,
                "sim_s": r["sim_s"], "run_realtime_factor": r["run_realtime_factor"],
                "flying": r["flying"], "outside_flight_s": r["outside_flight_s"]}
    return Case(f"campaign{jobs}", f"campaign, {4 * runs_per_scenario} runs, --jobs {jobs}",
                run)
