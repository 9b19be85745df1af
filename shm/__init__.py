"""silbridge.shm: the shared-memory transport between the bridge and the SIL FC.

A POSIX shared-memory segment, created by the bridge and attached by the FC,
holding two single-producer single-consumer rings of 64-byte records
(shm/include/sb_records.h, viewed from Python in .records) plus heartbeats
and lockstep words. Import the API from here::

    from silbridge.shm import Segment, Ring, ShmError
"""

from .errors import (
    AttachTimeoutError,
    LayoutMismatchError,
    OwnerDeadError,
    PeerBusyError,
    PermissionDeniedError,
    RecordKindError,
    RingRoleError,
    SegmentBusyError,
    SegmentClosedError,
    SegmentConfigError,
    SegmentMissingError,
    SegmentNameError,
    ShmError,
    StaleSegmentError,
)
from .segment import Ring, Segment, monotonic_ns, remove_stale

__all__ = [
    "Segment", "Ring", "ShmError", "remove_stale", "monotonic_ns",
    "AttachTimeoutError", "LayoutMismatchError", "OwnerDeadError", "PeerBusyError",
    "PermissionDeniedError", "RecordKindError", "RingRoleError", "SegmentBusyError",
    "SegmentClosedError", "SegmentConfigError", "SegmentMissingError", "SegmentNameError",
    "StaleSegmentError",
]
