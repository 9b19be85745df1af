"""Real-time pacing of the physics loop.

time.sleep() at 1 kHz wakes ~90 us late (PERF_NOTES), so the pacer sleeps
until a margin before the deadline and spins the rest on the monotonic clock.
Deadlines are absolute (t0 + k * period / speed), so a late step does not
push every later step back: the loop catches up, and the overrun is counted.

The spin runs in C with the GIL released (shm spin_until): spun in Python it kept the GIL, and
where the period is no longer than the spin (--speed 5 and up) the loop never let go of it; the
MAVLink server thread of a one-process `fly` then waited a switch interval (5 ms) for every
take, and its streams went out up to 3 s of sim time apart (tests/bridge/test_pacing.py).

busy_wait spins the whole period instead: on the 2-core VM a step that follows
a sleep runs with cold caches (p50 26 us against 6 us back to back, `python -m
silbridge.bridge.bench --paced`), which is most of the real-time jitter tail.
"""

from __future__ import annotations

import time

from silbridge.shm._ring import spin_until
from silbridge.shm.timer_slack import set_timer_slack_ns

_NS = 1_000_000_000


class Pacer:
    """Holds a loop to wall-clock deadlines start + k * dt_ns / speed."""

    def __init__(self, dt_ns: int, speed: float = 1.0, spin_ns: int = 200_000,
                 busy_wait: bool = False):
        if speed <= 0:
            raise ValueError("speed must be > 0")
        self.period_ns = dt_ns / speed
        self.spin_ns = 1 << 62 if busy_wait else spin_ns
        set_timer_slack_ns(1)   # exact wake-ups for this thread (shm/timer_slack.py)
        self.start_ns = time.monotonic_ns()
        self.late_steps = 0
        self.max_late_ns = 0
        # The worst stretch: consecutive steps each more than a period late (a host too
        # slow, or a long stall), from its first late deadline until a step is on time.
        self.worst_stretch_ns = 0
        self.worst_stretch_step = 0     # the step it began at (sim time = step * dt)
        self._stretch_from_ns: int | None = None
        self._stretch_step = 0

    def restart(self) -> None:
        self.start_ns = time.monotonic_ns()

    def wait_for_step(self, k: int) -> int:
        """Block until the deadline of step k; return how late we are (ns, >= 0)."""
        deadline = self.start_ns + int(k * self.period_ns)
        now = time.monotonic_ns()
        remaining = deadline - now
        if remaining > self.spin_ns:
            time.sleep((remaining - self.spin_ns) / _NS)
        now = spin_until(deadline)
        late = now - deadline
        if late > self.period_ns:
            self.late_steps += 1
            if self._stretch_from_ns is None:
                self._stretch_from_ns, self._stretch_step = deadline, k
        elif self._stretch_from_ns is not None:
            self._end_stretch(now)
        if late > self.max_late_ns:
            self.max_late_ns = late
        return late

    def finish(self, now_ns: int | None = None) -> None:
        """End the run: a stretch still open counts up to now."""
        if self._stretch_from_ns is not None:
            self._end_stretch(time.monotonic_ns() if now_ns is None else now_ns)

    def _end_stretch(self, now_ns: int) -> None:
        span = now_ns - self._stretch_from_ns
        if span > self.worst_stretch_ns:
            self.worst_stretch_ns, self.worst_stretch_step = span, self._stretch_step
        self._stretch_from_ns = None
