"""Spinning on a lockstep link instead of sleeping, where a core is free for it.

A lockstep frame with a foreign autopilot (ArduPilot SITL over JSON at 1 kHz, PX4 over HIL)
is a round trip between two processes. A server that sleeps in select() until the reply
comes pays a process wake-up per frame, which on the 2-core VM is tens of microseconds of a
~140 us frame: `python -m silbridge.tools.autopilots.ardupilot.speed` measured SITL's frame
plus the link at 85 us per packet with a sleeping server and 34 us with a spinning one (the
no-physics floor, 2026-11-25). Polling the socket without sleeping for a short budget first
removes that wake-up, but only where the spinning server has a core of its own beside the
autopilot's: with two runs on two cores (a campaign's `--jobs 2`), four processes share two
cores and a spinner steals the autopilot's time (`bench --fc ardupilot --scenarios S1 --runs 2
--duration 30`, same machine: --jobs 2 took 12.6 s without spinning, 14.2 s with; --jobs 1
29.4 s without, 21.5 s with). So campaigns spin only when every run has two cores, and a
single interactive run (a person watching, real time) never spins: it would burn a core
waiting for frames its pacing spaces out.
"""

from __future__ import annotations

import os
import time

# One wait's spin budget. A lockstep autopilot answers within some tens of microseconds;
# a longer silence (boot, its MAVLink or logger work) is slept through as before.
SPIN_US = 500.0


def usable_cores() -> int:
    """The cores this process may run on (its affinity, not the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):      # not Linux
        return os.cpu_count() or 1


def spin_budget_us(concurrent_runs: int) -> float:
    """SPIN_US when each of concurrent_runs lockstep pairs (autopilot + server) has two
    cores, else 0 (sleep at once)."""
    return SPIN_US if 2 * max(1, int(concurrent_runs)) <= usable_cores() else 0.0


def spin_poll(poll, budget_ns: int):
    """Call poll() (which must not block) until it returns something other than None or
    budget_ns of wall time pass; its last result."""
    got = poll()
    if got is not None or budget_ns <= 0:
        return got
    give_up = time.monotonic_ns() + budget_ns
    while got is None and time.monotonic_ns() < give_up:
        got = poll()
    return got
