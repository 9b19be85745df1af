"""A condition that must hold for a time before it counts (ArduCopter's checks that fire
after N seconds of a state: crash check, thrust loss): sim time, restarts when it breaks,
re-arms after it fires."""

from __future__ import annotations

from silbridge.shm.records import NS_PER_S


class HeldFor:
    def __init__(self, seconds: float):
        self.ns = int(round(seconds * NS_PER_S))
        self._since_ns = None

    def update(self, holds: bool, now_ns: int) -> bool:
        """True once `holds` has been true for the whole time up to now_ns (then starts over)."""
        if not holds:
            self._since_ns = None
            return False
        if self._since_ns is None:
            self._since_ns = now_ns
        if now_ns - self._since_ns >= self.ns:
            self._since_ns = None
            return True
        return False
