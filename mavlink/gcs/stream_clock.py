"""The telemetry streams' time base: the vehicle's simulated time, as ArduCopter SITL paces them.

ArduCopter SITL schedules every stream, HEARTBEAT included, on its simulated clock: at
--speedup 5 a 10 Hz GLOBAL_POSITION_INT comes 10 times per simulated second, 50 times per
wall second (measured on ArduCopter 4.6.0: 10.0 per sim s at 5x and 20x, 50.0 at 50 Hz,
HEARTBEAT 1.0 per sim s). So do we: the clock reads the sim time of the latest vehicle
snapshot (time_boot_ms, the time every message carries), and a client at `--speed 5` gets the
rates it asked for in the vehicle's time, whatever the speed, in lockstep too.

The server thread must wake when sim time reaches the next send, but sim time arrives only
with snapshots. A wake-up per snapshot from the vehicle thread would cost that thread a
system call, which also hands CPython's GIL back and forth: measured, it starved the server
thread (one pass per simulated second at 5x). So the server sleeps instead until the wall
time at which the clock's recent pace (``pace``, sim seconds per wall second over the last
``PACE_WINDOW_US``) brings it to the next send (``wall_us_until``); the vehicle thread is
untouched.

One difference, on purpose: ArduCopter falls silent while its physics stands still (it sends
nothing, HEARTBEAT included, while its JSON simulator does not answer). Here the FC may wait
for a bridge (`silbridge fc` started first, a paused run), and a ground station that hears no
HEARTBEAT reports the link lost; so once sim time has stood still for ``STILL_US`` of wall
time, the clock goes on with the wall clock until sim time moves again.

The clock never runs backwards (a restarted simulation, sim time back to 0): it carries an
offset instead, so every due time stays valid. Integer microseconds throughout, so a 50 Hz
stream on 20 ms snapshots hits every snapshot exactly (float seconds lose one now and then).
"""

from __future__ import annotations

STILL_US = 1_000_000        # wall time sim time may stand still before the wall clock takes over
PACE_WINDOW_US = 200_000    # wall time over which the pace is measured


class StreamClock:
    """now_us = sim time + offset (+ the wall time beyond STILL_US while sim time stands still).

    One per server, shared by every link's StreamSchedule; ``update`` runs on the server thread
    once per pass, everything else reads ``now_us``.
    """

    def __init__(self) -> None:
        self.now_us = 0
        self.pace = 0.0                     # clock us per wall us lately (0: not known yet)
        self._sim_us: int | None = None     # last sim time seen
        self._moved_wall_us = 0             # wall time it last changed
        self._offset_us = 0                 # clock minus sim time (stalls, restarts)
        self._pace_from: tuple[int, int] | None = None    # (wall us, clock us)

    def update(self, sim_us: int, wall_us: int) -> int:
        if sim_us != self._sim_us:
            self._sim_us, self._moved_wall_us = sim_us, wall_us
            # after a stall (or a restart) go on from where the clock is, never back
            self._offset_us = max(self._offset_us, self.now_us - sim_us)
        still_us = wall_us - self._moved_wall_us - STILL_US
        self.now_us = max(self.now_us, self._offset_us + sim_us + max(0, still_us))
        if self._pace_from is None:
            self._pace_from = (wall_us, self.now_us)
        elif wall_us - self._pace_from[0] >= PACE_WINDOW_US:
            self.pace = (self.now_us - self._pace_from[1]) / (wall_us - self._pace_from[0])
            self._pace_from = (wall_us, self.now_us)
        return self.now_us

    def wall_us_until(self, clock_us: int) -> float | None:
        """Wall microseconds until the clock reaches clock_us at its recent pace; None while
        the pace is unknown or nil (the server then polls at its idle period)."""
        if self.pace <= 0.0:
            return None
        return max(0, clock_us - self.now_us) / self.pace
