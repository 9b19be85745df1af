"""Segment: the shared-memory segment between the bridge and the SIL FC.

The bridge creates it (``Segment.create``, the owner) and the FC attaches
(``Segment.attach``, the peer); either process may also do both, e.g. for
fast single-process sweeps. The segment holds two rings (``sensors``: owner
to peer, ``actuators``: peer to owner), one heartbeat counter per side,
nine lockstep words (see shm/lockstep.py) and the per-ring counters.

Everything per record is in C (silbridge.shm._ring); this file adds the
class methods, the attach timeout and the context manager. The peer's side is the
FC loop's shared-memory transport (fc_sil/fc_transport.py FcTransport): `c_capsule()`
hands the mapping to the FC's C record router.
"""

from __future__ import annotations

import time

from . import _ring
from .errors import AttachTimeoutError, OwnerDeadError, SegmentMissingError

__all__ = ["Segment", "Ring", "remove_stale", "monotonic_ns", "serve_polls"]

Ring = _ring.Ring
monotonic_ns = _ring.monotonic_ns
# The FC process's lockstep loop in C (shm/src/serve.c; fc_sil/fc_loop.py run_fc):
# serve_polls(segment.c_capsule(), poll, until_ns, max_polls, timeout_s, python_kinds, records)
#   -> (polls, last_n, timed_out)
serve_polls = _ring.serve_polls

# Attach polls this often while the segment is missing or being created.
_ATTACH_POLL_S = 0.002


class Segment(_ring.SegmentBase):
    """One process's mapping of a segment; see the module docstring.

    Not thread-safe per ring side: one thread pushes a ring, one pops it.
    """

    @classmethod
    def create(cls, name: str, *, sensor_slots: int = 1 << 14, actuator_slots: int = 1 << 10,
               overwrite: bool = True, replace_stale: bool = True) -> "Segment":
        """Create and own segment `name` (the bridge side).

        overwrite: a full ring overwrites its oldest records (counted as
        overwritten by the consumer) instead of refusing pushes (rejected).
        replace_stale: silently replace a segment left by a crashed owner;
        a segment whose owner still runs is never touched (SegmentBusyError).
        Also reclaims other stale segments of this owner tag (shm/leftovers.py).
        """
        if replace_stale:
            # Leftovers of earlier crashed runs (same owner tag, over a minute old).
            from .leftovers import reclaim_stale
            reclaim_stale()
        seg = cls()
        seg._create(name, int(sensor_slots), int(actuator_slots), bool(overwrite),
                    bool(replace_stale))
        return seg

    @classmethod
    def attach(cls, name: str, *, timeout_s: float = 0.0) -> "Segment":
        """Attach to segment `name` as the peer (the FC side).

        Waits up to timeout_s for the bridge to create it, or to replace a
        stale one left by a crashed bridge; other errors (layout mismatch,
        permission, another FC attached) are raised at once.
        """
        deadline = time.monotonic() + max(0.0, timeout_s)
        while True:
            seg = cls()
            try:
                seg._attach(name)
                return seg
            except SegmentMissingError as exc:
                if time.monotonic() >= deadline:
                    if timeout_s > 0 and not isinstance(exc, AttachTimeoutError):
                        raise AttachTimeoutError(
                            f"{exc} (waited {timeout_s:g} s)", name=name) from None
                    raise
            except OwnerDeadError:
                if time.monotonic() >= deadline:
                    raise
            time.sleep(_ATTACH_POLL_S)

    def __enter__(self) -> "Segment":
        return self

    def __exit__(self, *exc_info) -> None:
        # Unlink while still holding the owner lock, then drop the mapping.
        if self.is_owner and not self.closed:
            self.unlink()
        self.close()

    def __repr__(self) -> str:
        role = "owner" if self.is_owner else "peer"
        state = "closed" if self.closed else f"peer pid {self.peer_pid}"
        return f"<Segment {self.name!r} {role}, {state}>"


def remove_stale(name: str) -> bool:
    """Remove segment `name` if its owner is gone; True if one was removed.

    Raises SegmentBusyError if a live bridge owns it.
    """
    return _ring.remove_stale(name)

