"""FcTransport: what the FC loop (fc_sil/fc_loop.py) needs from the link to the bridge.

Two links satisfy it: the shared-memory segment (shm/segment.py, the FC's peer side) and
the MAVLink HIL links (mavlink/hil/hil_fc_end.py HilFcEnd, UDP or TCP). The loop speaks
only this surface; which poll it runs is decided once, from `c_capsule()`: a segment
hands its rings to the C record router (fc_sil/ext/record_router.c), a link whose
records travel through Python returns None and the loop polls in Python.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class SensorSource(Protocol):
    """The sensor side: records from the bridge, in publication order."""

    def pop_into(self, out: np.ndarray) -> int:
        """Move up to len(out) waiting records into out; returns how many."""

    def wait(self, timeout_s: float, *, yield_s: float = 200e-6) -> bool:
        """Wait up to timeout_s for a record; True if one waits. yield_s: how long the
        shared-memory ring yields before it sleeps (a link that blocks in select ignores it)."""


class ActuatorSink(Protocol):
    """The actuator side: PWM records to the bridge."""

    def push_batch(self, pwm: np.ndarray) -> int:
        """Publish the PWM records; returns how many were taken."""


class FcTransport(Protocol):
    """The FC's end of the bridge link: two record streams and the lockstep words
    (shm/lockstep.py gives their meaning)."""

    sensors: SensorSource
    actuators: ActuatorSink

    def set_word(self, i: int, value: int) -> None: ...

    def word(self, i: int) -> int: ...

    def beat(self) -> None:
        """Tell the bridge this side is alive."""

    def peer_alive(self) -> bool:
        """False once the bridge is gone."""

    def c_capsule(self) -> object | None:
        """The link for the C record router (a capsule, shm/include/sb_capi.h), or None
        when records cross in Python: the FC loop then polls in Python."""
