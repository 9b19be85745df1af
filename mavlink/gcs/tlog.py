"""MAVLink telemetry log (.tlog): the GCS link's traffic, as MAVProxy and QGroundControl write it.

A tlog is a plain concatenation of records, each the wall-clock time in
microseconds since the Unix epoch as a big-endian uint64, then one MAVLink
frame exactly as it went over the wire. Both directions go in, as MAVProxy
logs them: every frame the vehicle sent to a GCS and every valid frame a GCS
sent to it. A message broadcast to several GCS links is one record (the same
frame, once), as a GCS that reads the vehicle over one link would have
logged it. Readers: pymavlink's mavutil.mavlink_connection("x.tlog"),
mavlogdump.py, MAVExplorer, QGroundControl's log replay.

Writes come from the GCS server's thread (and, for a status text sent on the
vehicle's behalf, possibly another), so they take a lock; each record is one
unbuffered write (a few hundred a second), so a killed run keeps every record.
"""

from __future__ import annotations

import struct
import threading
import time

_STAMP = struct.Struct(">Q")


class TlogError(Exception):
    user_facing = True


class TlogWriter:
    def __init__(self, path, clock=time.time):
        try:
            self._f = open(path, "wb", buffering=0)   # a killed run keeps every record
        except OSError as exc:
            raise TlogError(f"cannot create the telemetry log {path}: {exc.strerror}; "
                            "choose a writable path for --tlog") from exc
        self.path = path
        self._clock = clock
        self._lock = threading.Lock()
        self.records = 0

    def write(self, frame: bytes) -> None:
        """One MAVLink frame (msg.get_msgbuf()), stamped now."""
        if not frame:
            return
        stamp = _STAMP.pack(int(self._clock() * 1e6))
        with self._lock:
            if self._f.closed:
                return
            self._f.write(stamp + bytes(frame))
            self.records += 1

    def message(self, msg) -> None:
        """A pymavlink message already packed (sent) or decoded (received)."""
        self.write(msg.get_msgbuf())

    def close(self) -> None:
        with self._lock:
            if not self._f.closed:
                self._f.close()
