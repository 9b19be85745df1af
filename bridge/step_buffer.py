"""The preallocated record buffer one physics step is written into.

Records use the shm contract (silbridge.shm.records): 64-byte slots, header
{kind, flags, seq, sim_ns, wall_ns}. The buffer is a bytearray with numpy views
over it: the C step kernel (bridge/src/stepmodule.c) writes the IMU and
ground-truth records in place, `Struct.pack_into` the low-rate ones and the
Python reference kernel's, and the oversampled IMU block is written through uint32/float32/int64 views in
four vectorised assignments. wall_ns stays 0 (the ring stamps it).

`records(count)` returns a RECORD_DTYPE view of the first `count` slots: it is
valid until the next step overwrites the buffer; copy it to keep it.
"""

from __future__ import annotations

import struct

import numpy as np

from silbridge.shm.records import FLAG_STEP_END, RECORD_DTYPE, RECORD_SIZE, Kind

HEADER = "HHIqq"
IMU_FMT = HEADER + "3f3ffIII"
GT_ATT_FMT = HEADER + "4f3f3f"
GT_NAV_FMT = HEADER + "3d3fB3x"
BARO_FMT = HEADER + "ff32x"
MAG_FMT = HEADER + "3f28x"
GNSS_FMT = HEADER + "iii3fHHBB10x"
SETPOINT_FMT = HEADER + "4fI20x"

IMU = struct.Struct("<" + IMU_FMT)
GT = struct.Struct("<" + GT_ATT_FMT + GT_NAV_FMT)
BARO = struct.Struct("<" + BARO_FMT)
MAG = struct.Struct("<" + MAG_FMT)
GNSS = struct.Struct("<" + GNSS_FMT)
SETPOINT = struct.Struct("<" + SETPOINT_FMT)

for _s, _n in ((IMU, 1), (GT, 2), (BARO, 1), (MAG, 1), (GNSS, 1), (SETPOINT, 1)):
    assert _s.size == _n * RECORD_SIZE, (_s.format, _s.size)

_FLAGS_OFFSET = 2  # byte offset of the u16 flags in a slot; STEP_END is its low bit


class StepBuffer:
    def __init__(self, capacity: int):
        self.capacity = capacity
        self.buf = bytearray(capacity * RECORD_SIZE)
        self.generic = np.frombuffer(self.buf, dtype=RECORD_DTYPE)
        self.u32 = np.frombuffer(self.buf, dtype="<u4").reshape(capacity, 16)
        self.f32 = np.frombuffer(self.buf, dtype="<f4").reshape(capacity, 16)
        self.i64 = np.frombuffer(self.buf, dtype="<i8").reshape(capacity, 8)
        self._views = [self.generic[:i] for i in range(capacity + 1)]
        self._imu_templates: dict[int, np.ndarray] = {}
        self._aranges: dict[int, np.ndarray] = {}
        self._payload_views: dict[int, np.ndarray] = {}

    def finish(self, count: int) -> np.ndarray:
        """Mark the last record STEP_END and return the step's records."""
        self.buf[(count - 1) * RECORD_SIZE + _FLAGS_OFFSET] = FLAG_STEP_END
        return self._views[count]

    def write_imu_headers(self, n: int, seq0: int, times_ns: np.ndarray) -> None:
        """Headers and index fields of n IMU records in slots 0..n-1 (payload: imu_payload)."""
        tpl = self._imu_templates.get(n)
        if tpl is None:
            tpl = np.zeros((n, 16), dtype="<u4")
            tpl[:, 0] = int(Kind.IMU)          # kind | flags << 16 (flags 0)
            tpl[:, 13] = np.arange(n)          # sample_index
            tpl[:, 14] = n                     # samples_per_step
            self._imu_templates[n] = tpl
            self._aranges[n] = np.arange(n, dtype=np.int64)
        self.u32[:n] = tpl
        self.u32[:n, 1] = (self._aranges[n] + seq0) & 0xFFFFFFFF
        self.i64[:n, 1] = times_ns

    def imu_payload(self, n: int) -> np.ndarray:
        """(n, 7) float32 view: accel xyz, gyro xyz, temperature of IMU slots 0..n-1."""
        v = self._payload_views.get(n)
        if v is None:
            v = self._payload_views[n] = self.f32[:n, 6:13]
        return v
