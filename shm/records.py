"""The Python view of shm/include/sb_records.h.

Every record is one 64-byte little-endian slot: a 24-byte header and a
40-byte payload. ``RECORD_DTYPE`` is the generic view (header + raw payload)
that mixed-kind batches use; ``DTYPES[kind]`` is the full 64-byte view of one
kind, so ``batch[batch["kind"] == IMU].view(DTYPES[IMU])`` reads IMU fields
without copying field by field. tests/shm/test_layout.py checks every offset
against the C compiler's offsetof.

Every other reader of a slot is derived from these dtypes, never spelled by hand:
`record_struct` builds the `struct.Struct` of a slot (or of some of its fields) for
hot paths that pack or unpack bytes directly, `word_index` finds a field in a u16/u32/f32/
i64 row view of a slot, `FLAGS_OFFSET` is where STEP_END is set. tests/shm/test_layout.py
checks them and every reader built from them against the C side too.
"""

from __future__ import annotations

import enum
import struct

import numpy as np

RECORDS_VERSION = 1
NS_PER_S = 1_000_000_000   # sim_ns and wall_ns count nanoseconds: the project's one copy
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
    ESC = 9
    BATTERY = 10
    FAULT = 11


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

# One ESC's telemetry report (one record per motor per epoch; see sb_esc in sb_records.h).
ESC_DTYPE = _record([
    ("motor", "u1"),
    ("motor_count", "u1"),
    ("reserved0", "<u2"),
    ("rpm", "<f4"),
    ("voltage_v", "<f4"),
    ("current_a", "<f4"),
    ("temperature_c", "<f4"),
    ("consumption_mah", "<f4"),
])

# The physics-side battery pack, as a smart battery reports it (see sb_battery in sb_records.h).
BATTERY_DTYPE = _record([
    ("voltage_v", "<f4"),
    ("current_a", "<f4"),
    ("consumed_mah", "<f4"),
    ("remaining", "<f4"),
    ("temperature_c", "<f4"),
    ("lowest_cell_v", "<f4"),
    ("cell_count", "u1"),
])

# A fault the FC switches on or off, forwarded to the bridge's fault engine (see sb_fault in
# sb_records.h; codes and parameter slots: shm/fault_catalog.py).
FAULT_DTYPE = _record([
    ("action", "u1"),
    ("unit", "u1"),
    ("type", "u1"),
    ("instance", "u1"),
    ("params", "<f4", (9,)),
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
    Kind.ESC: ESC_DTYPE,
    Kind.BATTERY: BATTERY_DTYPE,
    Kind.FAULT: FAULT_DTYPE,
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


# Plain ints of the kinds, for hot paths that compare or pack kinds many times a step (an
# IntEnum member costs an attribute lookup and an __index__ call each time).
KIND_IMU = int(Kind.IMU)
KIND_BARO = int(Kind.BARO)
KIND_MAG = int(Kind.MAG)
KIND_GNSS = int(Kind.GNSS)
KIND_GT_ATT = int(Kind.GT_ATT)
KIND_GT_NAV = int(Kind.GT_NAV)
KIND_PWM = int(Kind.PWM)
KIND_SETPOINT = int(Kind.SETPOINT)
KIND_ESC = int(Kind.ESC)
KIND_BATTERY = int(Kind.BATTERY)
KIND_FAULT = int(Kind.FAULT)

FLAGS_OFFSET = RECORD_DTYPE.fields["flags"][1]      # byte offset of the u16 flags in a slot
HEADER_SIZE = RECORD_DTYPE.fields["payload"][1]     # bytes before the payload of every kind

# numpy base type -> struct code; "<" formats so wire widths never depend on the host.
_STRUCT_CODE = {"f4": "f", "f8": "d", "i1": "b", "u1": "B", "i2": "h", "u2": "H",
                "i4": "i", "u4": "I", "i8": "q", "u8": "Q"}


def _dtype(kind: Kind) -> np.dtype:
    """The full view of one kind; Kind.NONE means the generic header + raw payload view."""
    return RECORD_DTYPE if Kind(kind) is Kind.NONE else DTYPES[Kind(kind)]


def _field_code(dt: np.dtype, name: str) -> str:
    ft = dt.fields[name][0]
    base = ft.base if ft.subdtype else ft
    count = int(np.prod(ft.shape)) if ft.shape else 1
    if base.kind == "V":            # raw bytes: the generic payload, padding
        return f"{ft.itemsize}{'x' if name.startswith('_') else 's'}"
    code = _STRUCT_CODE[f"{base.kind}{base.itemsize}"]
    return f"{count}{code}" if count > 1 else code


def record_format(kind: Kind, fields=None) -> str:
    """The struct format (without byte-order prefix) of a slot of `kind`.

    fields None: the whole 64-byte slot, header included, padding as `x`. Otherwise only the
    named fields, in slot order, with `x` padding from the slot start to each one (the format
    ends at the last field). Without the prefix so that consecutive slots concatenate."""
    dt = _dtype(kind)
    if fields is None:
        return "".join(_field_code(dt, name) for name in dt.names)
    parts, pos = [], 0
    for name in fields:
        if name not in dt.fields:
            raise ValueError(f"{Kind(kind).name} records have no field {name!r}")
        off = dt.fields[name][1]
        if off < pos:
            raise ValueError(f"field {name!r} is listed after a later one: list them in slot order")
        if off > pos:
            parts.append(f"{off - pos}x")
        parts.append(_field_code(dt, name))
        pos = off + dt.fields[name][0].itemsize
    return "".join(parts)


def record_struct(kind: Kind, fields=None) -> struct.Struct:
    """struct.Struct reading/writing a slot of `kind` from its start (see record_format).

    Build it once at import: hot paths call its pack_into/unpack_from thousands of times
    a second."""
    return struct.Struct("<" + record_format(kind, fields))


def word_index(kind: Kind, field: str, itemsize: int) -> int:
    """Index of `field` in a row of a slot viewed as words of `itemsize` bytes (2: u16,
    4: u32/f32, 8: i64/f64), e.g. `u32.reshape(-1, 16)[:, word_index(Kind.IMU, "seq", 4)]`."""
    off = _dtype(kind).fields[field][1]
    if off % itemsize:
        raise ValueError(f"{field!r} at byte {off} is not on a {itemsize}-byte word")
    return off // itemsize
