"""The vehicle's recent snapshots, in order, for telemetry streamed on sim time.

The vehicle thread publishes one snapshot per outer-loop step (50 Hz of sim time, so 250 per
wall second at `--speed 5`). The server thread cannot run that often: while the control loop
runs Python code, CPython hands the GIL to another thread only every switch interval (5 ms),
and measured at 5x a server reading only the latest snapshot sent a 50 Hz stream 20 times per
simulated second. ArduCopter sends every message with the state of its own instant, so the
server must see every instant: ``put`` keeps the last ``SIZE`` snapshots, and a telemetry
pass ``take``s every one it has not seen yet, in order, and runs the streams over each.

One writer (the vehicle thread, ``put``), one reader (the server thread, ``take``). The
writer stores the slot, then bumps ``written``; the reader reads ``written``, then copies the
slots (one list copy: atomic under the GIL), and keeps only slots the writer cannot have
reused in between (``MARGIN`` of them). A reader that fell further behind loses the oldest
(``lost``): its streams then skip rather than burst (streams.py).
"""

from __future__ import annotations

from silbridge.mavlink.gcs.vehicle_api import VehicleSnapshot

SIZE = 64       # 1.28 s of sim time at 50 Hz: a server pass comes far more often, even at 30x
MARGIN = 16     # slots the writer may fill between the reader's two reads


class SnapshotRing:
    def __init__(self) -> None:
        self._slots: list[VehicleSnapshot | None] = [None] * SIZE
        self.written = 0        # snapshots put so far (the writer's counter)
        self._read = 0          # snapshots taken so far (the reader's counter)
        self.lost = 0           # snapshots overwritten before they were taken

    def put(self, snapshot: VehicleSnapshot) -> None:
        self._slots[self.written % SIZE] = snapshot
        self.written += 1

    def take(self) -> list[VehicleSnapshot]:
        """Every snapshot put since the last take, oldest first (empty if none)."""
        end = self.written
        slots = self._slots[:]
        start = max(self._read, end - (SIZE - MARGIN))
        self.lost += start - self._read
        self._read = end
        return [slots[i % SIZE] for i in range(start, end)]
