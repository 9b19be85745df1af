"""The preallocated record buffer one physics step is written into.

Records use the shm contract (silbridge.shm.records): 64-byte slots, header
{kind, flags, seq, sim_ns, wall_ns}. The buffer is a bytearray with numpy views
over it: the C step kernel (bridge/src/stepmodule.c) writes the IMU and
ground-truth records in place, `Struct.pack_into` the low-rate ones and the
Python reference kernel's, and the oversampled IMU block is written through
uint32/float32/int64 views in four vectorised assignments. wall_ns stays 0 (the
ring stamps it). Every format and word index here is derived from the dtypes of
shm/records.py, so the slot layout is spelled out there only.

`finish(count)` returns a RECORD_DTYPE view of the first `count` slots: it is
valid until the next step overwrites the buffer; copy it to keep it.
"""

from __future__ import annotations

import struct

import numpy as np

from silbridge.shm.records import (FLAG_STEP_END, FLAGS_OFFSET, RECORD_DTYPE, RECORD_SIZE, Kind,
                                   record_format, record_struct, word_index)

# Whole-slot writers, derived from shm/records.py's dtypes (tests/shm/test_layout.py checks
# them against the C structs). GT writes the two ground-truth slots in one call.
IMU = record_struct(Kind.IMU)
GT = struct.Struct("<" + record_format(Kind.GT_ATT) + record_format(Kind.GT_NAV))
BARO = record_struct(Kind.BARO)
MAG = record_struct(Kind.MAG)
GNSS = record_struct(Kind.GNSS)
SETPOINT = record_struct(Kind.SETPOINT)

# Word columns of the IMU block's vectorised writes, in the u32/f32 (4-byte) and i64 rows.
_W32 = RECORD_SIZE // 4
_W64 = RECORD_SIZE // 8
_KIND_W = word_index(Kind.IMU, "kind", 4)                 # kind | flags << 16
_SEQ_W = word_index(Kind.IMU, "seq", 4)
_SIM_NS_W = word_index(Kind.IMU, "sim_ns", 8)
_SAMPLE_INDEX_W = word_index(Kind.IMU, "sample_index", 4)
_SAMPLES_PER_STEP_W = word_index(Kind.IMU, "samples_per_step", 4)
_PAYLOAD_W = word_index(Kind.IMU, "accel_frd_m_s2", 4)    # accel xyz, gyro xyz, temperature
_PAYLOAD_END_W = word_index(Kind.IMU, "temperature_c", 4) + 1


class StepBuffer:
    def __init__(self, capacity: int):
        self.capacity = capacity
        self.buf = bytearray(capacity * RECORD_SIZE)
        self.generic = np.frombuffer(self.buf, dtype=RECORD_DTYPE)
        self.u32 = np.frombuffer(self.buf, dtype="<u4").reshape(capacity, _W32)
        self.f32 = np.frombuffer(self.buf, dtype="<f4").reshape(capacity, _W32)
        self.i64 = np.frombuffer(self.buf, dtype="<i8").reshape(capacity, _W64)
        self._views = [self.generic[:i] for i in range(capacity + 1)]
        self._seq = self.u32[:, _SEQ_W]           # one column per slot: [:n] is a cheap slice
        self._sim_ns = self.i64[:, _SIM_NS_W]
        self._imu_templates: dict[int, np.ndarray] = {}
        self._aranges: dict[int, np.ndarray] = {}
        self._payload_views: dict[int, np.ndarray] = {}

    def finish(self, count: int) -> np.ndarray:
        """Mark the last record STEP_END and return the step's records."""
        self.buf[(count - 1) * RECORD_SIZE + FLAGS_OFFSET] = FLAG_STEP_END  # low byte
        return self._views[count]

    def write_imu_headers(self, n: int, seq0: int, times_ns: np.ndarray) -> None:
        """Headers and index fields of n IMU records in slots 0..n-1 (payload: imu_payload)."""
        tpl = self._imu_templates.get(n)
        if tpl is None:
            tpl = np.zeros((n, _W32), dtype="<u4")
            tpl[:, _KIND_W] = int(Kind.IMU)    # flags 0
            tpl[:, _SAMPLE_INDEX_W] = np.arange(n)
            tpl[:, _SAMPLES_PER_STEP_W] = n
            self._imu_templates[n] = tpl
            self._aranges[n] = np.arange(n, dtype=np.int64)
        self.u32[:n] = tpl
        self._seq[:n] = (self._aranges[n] + seq0) & 0xFFFFFFFF
        self._sim_ns[:n] = times_ns

    def imu_payload(self, n: int) -> np.ndarray:
        """(n, 7) float32 view: accel xyz, gyro xyz, temperature of IMU slots 0..n-1."""
        v = self._payload_views.get(n)
        if v is None:
            v = self._payload_views[n] = self.f32[:n, _PAYLOAD_W:_PAYLOAD_END_W]
        return v
