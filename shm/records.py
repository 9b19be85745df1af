"""The Python view of shm/include/sb_records.h.

Every record is one 64-byte little-endian slot: a 24-byte header and a
40-byte payload. ``RECORD_DTYPE`` is the generic view (header + raw payload)
that mixed-kind batches use; ``DTYPES[kind]`` is the full 64-byte view of one
kind, so ``batch[batch["kind"] == IMU].view(DTYPES[IMU])`` reads IMU fields
without copying field by field. tests/shm/test_layout.py checks every offset
against the C compiler's offsetof.
"""

from __future__ import annotations

import enum

import numpy as np

RECORDS_VERSION = 1
RECORD_SIZE = 64
PWM_MAX_CHANNELS = 8
FLAG_STEP_END = 0x0001


class Kind(enum.IntEnum):
    NONE = 0
    IMU = 1
    BARO = 2
    MAG = 3
    GNSS = 4
    GT_ATT = 5
    GT_NAV = 6
    PWM = 7
    SETPOINT = 8


_HEADER = [
    ("kind", "<u2"),
    ("flags", "<u2"),
    ("seq", "<u4"),
    ("sim_ns", "<i8"),
    ("wall_ns", "<i8"),
]


def _record(payload: list[tuple]) -> np.dtype:
    dt = np.dtype(_HEADER + payload)
    pad = RECORD_SIZE - dt.itemsize
    if pad < 0:
        raise AssertionError(f"record payload too large: {payload}")
    if pad:
        dt = np.dtype(_HEADER + payload + [("_pad", f"V{pad}")])
    return dt


RECORD_DTYPE = _record([("payload", "V40")])

IMU_DTYPE = _record([
    ("accel_frd_m_s2", "<f4", (3,)),
    ("gyro_frd_rad_s", "<f4", (3,)),
    ("temperature_c", "<f4"),
    ("sample_index", "<u4"),
    ("samples_per_step", "<u4"),
    ("reserved", "<u4"),
])

BARO_DTYPE = _record([
    ("pressure_pa", "<f4"),
    ("temperature_c", "<f4"),
])

MAG_DTYPE = _record([
    ("field_frd_gauss", "<f4", (3,)),
])

GNSS_DTYPE = _record([
    ("lat_e7", "<i4"),
    ("lon_e7", "<i4"),
    ("alt_mm", "<i4"),
    ("vel_ned_m_s", "<f4", (3,)),
    ("eph_cm", "<u2"),
    ("epv_cm", "<u2"),
    ("fix_type", "u1"),
    ("satellites", "u1"),
])

GT_ATT_DTYPE = _record([
    ("q_wxyz", "<f4", (4,)),
    ("rates_frd_rad_s", "<f4", (3,)),
    ("specific_force_frd_m_s2", "<f4", (3,)),
])

GT_NAV_DTYPE = _record([
    ("pos_ned_m", "<f8", (3,)),
    ("vel_ned_m_s", "<f4", (3,)),
    ("on_ground", "u1"),
])

PWM_DTYPE = _record([
    ("pwm_us", "<u2", (PWM_MAX_CHANNELS,)),
    ("channel_count", "u1"),
    ("armed", "u1"),
    ("reserved0", "<u2"),
    ("fc_step_seq", "<u4"),
    ("imu_sim_ns", "<i8"),
])

SETPOINT_DTYPE = _record([
    ("roll_rad", "<f4"),
    ("pitch_rad", "<f4"),
    ("yaw_rad", "<f4"),
    ("altitude_m", "<f4"),
    ("mask", "<u4"),
])

DTYPES: dict[Kind, np.dtype] = {
    Kind.IMU: IMU_DTYPE,
    Kind.BARO: BARO_DTYPE,
    Kind.MAG: MAG_DTYPE,
    Kind.GNSS: GNSS_DTYPE,
    Kind.GT_ATT: GT_ATT_DTYPE,
    Kind.GT_NAV: GT_NAV_DTYPE,
    Kind.PWM: PWM_DTYPE,
    Kind.SETPOINT: SETPOINT_DTYPE,
}

for _kind, _dt in DTYPES.items():
    assert _dt.itemsize == RECORD_SIZE, (_kind, _dt.itemsize)


def empty(kind: Kind, n: int) -> np.ndarray:
    """n zeroed records of one kind with the kind field already set."""
    arr = np.zeros(n, dtype=DTYPES[Kind(kind)])
    arr["kind"] = int(kind)
    return arr


def as_generic(arr: np.ndarray) -> np.ndarray:
    """View any record array as RECORD_DTYPE (no copy)."""
    if arr.dtype.itemsize != RECORD_SIZE:
        raise ValueError(f"records are {RECORD_SIZE} bytes, got itemsize {arr.dtype.itemsize}")
    return arr.view(RECORD_DTYPE)


def view_kind(arr: np.ndarray, kind: Kind) -> np.ndarray:
    """View a record array as one kind (no copy); the caller filters by kind first."""
    return arr.view(DTYPES[Kind(kind)])
