"""What the serve loops of the foreign-autopilot servers share: when a run ends, what it returns.

A server for a foreign autopilot (ArduPilot's JSON physics,
bridge/autopilots/ardupilot/server.py; PX4's simulator link, bridge/autopilots/px4/server.py)
steps our physics for each message of the autopilot until the sim time reaches the run's
duration, the vehicle crashes, or the caller's `stop()` says the run is over (the autopilot
exited, its driver failed, the flight is done). Both loops ask the same two questions after
each step and end with the same result, so `stopped_by` reads alike in every summary:
"duration", "crash" or "stop".
"""

from __future__ import annotations

import time
from dataclasses import dataclass

_NS = 1_000_000_000


def stop_asked(stop) -> bool:
    """The caller's stop() (optional) says the run is over."""
    return stop is not None and stop()


def ended_by(sim, stop) -> str | None:
    """After a step: "crash" when the vehicle crashed, "stop" when stop() asks, else None."""
    if sim.crashed and sim.end_on_crash:
        return "crash"
    if stop_asked(stop):
        return "stop"
    return None


@dataclass
class ServeResult:
    """One serve loop's run: sim and wall time, the link's counters, how it ended."""
    sim_s: float
    wall_s: float
    stats: dict
    crashed: bool
    crash_reason: str = ""
    stopped_by: str = "duration"

    @classmethod
    def of(cls, sim, t0: float, stats: dict, stopped_by: str, **extra) -> "ServeResult":
        """The result of a loop that started at monotonic t0 and ended now."""
        return cls(sim_s=sim.sim_ns / _NS, wall_s=time.monotonic() - t0, stats=stats,
                   crashed=bool(sim.crashed), crash_reason=sim.crash_reason,
                   stopped_by=stopped_by, **extra)
