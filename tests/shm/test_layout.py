"""The Python record views agree with the C structs, field by field.

A tiny C program, generated from the numpy dtypes of silbridge.shm.records
and compiled with `cc` against shm/include/sb_records.h, prints offsetof,
sizeof and the element type of every field of every record kind; each must
equal the dtype's offset, itemsize and base type. Every reader derived from
those dtypes (the `struct.Struct`s of record_struct and the modules that pack
or unpack slots through them, word_index, FLAGS_OFFSET) is checked against the
same C output, so a field that moves in C breaks here, not in a flight. The
extension's own view of the segment structs is checked against the static
layout too.
"""

from __future__ import annotations

import re
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

from silbridge.bridge import step_buffer
from silbridge.bridge.autopilots.ardupilot import physics as ardupilot_physics
from silbridge.mavlink.hil import hil_codec, hil_fault, hil_pwm
from silbridge.shm import _ring, errors, record_structs
from silbridge.shm.records import (DTYPES, FLAG_STEP_END, FLAGS_OFFSET, HEADER_SIZE, IMU_DTYPE,
                                   RECORD_DTYPE, RECORD_SIZE, RECORDS_VERSION, Kind,
                                   record_struct, word_index)

INCLUDE = Path(__file__).resolve().parents[2] / "shm" / "include"

# Kind -> member of the payload union in sb_record.
UNION_MEMBER = {
    Kind.IMU: "imu", Kind.BARO: "baro", Kind.MAG: "mag", Kind.GNSS: "gnss",
    Kind.GT_ATT: "gt_att", Kind.GT_NAV: "gt_nav", Kind.PWM: "pwm", Kind.SETPOINT: "setpoint",
    Kind.ESC: "esc",
    Kind.BATTERY: "battery",
    Kind.FAULT: "fault",
}
HEADER_FIELDS = ("kind", "flags", "seq", "sim_ns", "wall_ns")

C_TYPECODE = """
#define TYPECODE(x) _Generic((x), float: "f4", double: "f8", int8_t: "i1", uint8_t: "u1", \\
    int16_t: "i2", uint16_t: "u2", int32_t: "i4", uint32_t: "u4", int64_t: "i8", \\
    uint64_t: "u8", default: "??")
"""


def _fields(dtype: np.dtype):
    """(name, offset, itemsize, base typecode, element count) of named fields."""
    for fname, (ft, off) in dtype.fields.items():
        if fname.startswith("_") or fname == "payload":
            continue
        base = ft.base if ft.subdtype else ft
        count = int(np.prod(ft.shape)) if ft.shape else 1
        yield fname, off, ft.itemsize, f"{base.kind}{base.itemsize}", count


def _program() -> tuple[str, dict]:
    lines, expect = [], {}
    for fname, off, size, code, count in _fields(RECORD_DTYPE):
        expect[f"h.{fname}"] = (off, size, code, count)
    for kind, member in UNION_MEMBER.items():
        for fname, off, size, code, count in _fields(DTYPES[kind]):
            path = f"h.{fname}" if fname in HEADER_FIELDS else f"u.{member}.{fname}"
            expect[path] = (off, size, code, count)
    for path in expect:
        elem = f"R.{path}[0]" if expect[path][3] > 1 else f"R.{path}"
        lines.append(
            f'printf("%s %zu %zu %s %zu\\n", "{path}", offsetof(sb_record, {path}), '
            f'sizeof(R.{path}), TYPECODE({elem}), sizeof(R.{path}) / sizeof({elem}));')
    src = ("#include <stddef.h>\n#include <stdio.h>\n#include <stdint.h>\n"
           '#include "sb_records.h"\n' + C_TYPECODE +
           "int main(void) {\n    sb_record R;\n    (void)R;\n"
           '    printf("sizeof %zu %u\\n", sizeof(sb_record), SB_RECORDS_VERSION);\n    '
           + "\n    ".join(lines) + "\n    return 0;\n}\n")
    return src, expect


@pytest.fixture(scope="module")
def c_layout(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.fail("no C compiler: the layout check needs `cc` (the package build needs it too)")
    src, expect = _program()
    d = tmp_path_factory.mktemp("layout")
    (d / "layout.c").write_text(src)
    subprocess.run([cc, "-std=c11", "-Wall", "-Werror", f"-I{INCLUDE}", "layout.c", "-o",
                    "layout"], cwd=d, check=True, capture_output=True)
    out = subprocess.run([str(d / "layout")], check=True, capture_output=True,
                         text=True).stdout.splitlines()
    return out, expect


def test_record_size_and_version(c_layout):
    out, _ = c_layout
    size, version = out[0].split()[1:]
    assert int(size) == RECORD_SIZE == RECORD_DTYPE.itemsize
    assert int(version) == RECORDS_VERSION


def test_every_field_of_every_kind_matches_c(c_layout):
    out, expect = c_layout
    seen = {}
    for line in out[1:]:
        path, off, size, code, count = line.split()
        seen[path] = (int(off), int(size), code, int(count))
    assert seen.keys() == expect.keys()
    mismatches = {p: (seen[p], expect[p]) for p in expect if seen[p] != expect[p]}
    assert not mismatches, f"(C, Python) differ: {mismatches}"


def test_every_kind_has_a_view_and_a_union_member():
    assert set(DTYPES) == set(UNION_MEMBER) == set(Kind) - {Kind.NONE}
    assert _ring.KIND_COUNT == len(Kind)
    for dt in DTYPES.values():
        assert dt.itemsize == RECORD_SIZE


def test_extension_segment_layout():
    lay = _ring.layout()
    assert lay["sizeof_record"] == RECORD_SIZE and lay["sizeof_header"] == 24
    assert lay["sizeof_ring_ctl"] == 192
    assert lay["ring_head"] == 64 and lay["ring_tail"] == 128  # each index on its own line
    assert lay["seg_owner_line"] == 64 and lay["seg_peer_line"] == 128
    assert lay["seg_words"] == 192 and lay["words"] == 9     # FC_SYNC_NS: the ninth
    assert lay["sizeof_seg_header"] <= lay["header_bytes"] == 4096
    assert lay["records_version"] == RECORDS_VERSION


def test_status_codes_agree_with_the_extension():
    for code in ("E_NAME", "E_CONFIG", "E_MISSING", "E_CREATING", "E_BUSY", "E_STALE",
                 "E_PERM", "E_MAGIC", "E_VERSION", "E_LAYOUT", "E_PEER_BUSY", "E_OS"):
        assert getattr(errors, code) == getattr(_ring, code), code
    assert _ring.SHM_PREFIX == "/" + errors.SHM_PREFIX


# struct code -> the C typecode the layout program prints.
STRUCT_TO_C = {"f": "f4", "d": "f8", "b": "i1", "B": "u1", "h": "i2", "H": "u2", "i": "i4",
               "I": "u4", "q": "i8", "Q": "u8"}


def _c_fields(c_layout) -> dict:
    """C path -> (offset, size, typecode, count), from the compiled program's output."""
    out, _ = c_layout
    return {path: (int(off), int(size), code, int(count))
            for path, off, size, code, count in (line.split() for line in out[1:])}


def _c_elements(c_layout, kind: Kind, base: int = 0) -> list:
    """(byte offset, typecode) of every scalar element of one kind's C record, in slot order."""
    member = f"u.{UNION_MEMBER[kind]}."
    elems = []
    for path, (off, size, code, count) in _c_fields(c_layout).items():
        if path.startswith("h.") or path.startswith(member):
            elems += [(base + off + j * (size // count), code) for j in range(count)]
    return sorted(set(elems))


def _struct_elements(s: struct.Struct) -> list:
    """(byte offset, typecode) of every value a little-endian, unaligned struct packs."""
    assert s.format[0] == "<"
    elems, pos = [], 0
    for n, code in re.findall(r"(\d*)([a-zA-Z?])", s.format[1:]):
        n = int(n or 1)
        if code == "x":
            pos += n
            continue
        width = struct.calcsize("<" + code)
        elems += [(pos + j * width, STRUCT_TO_C[code]) for j in range(n)]
        pos += n * width
    assert pos == s.size
    return elems


# Whole-slot writers/readers: they must pack every C field of their kinds, at C's offsets.
WHOLE_SLOTS = {
    "step_buffer.IMU": (step_buffer.IMU, [Kind.IMU]),
    "step_buffer.GT": (step_buffer.GT, [Kind.GT_ATT, Kind.GT_NAV]),
    "step_buffer.BARO": (step_buffer.BARO, [Kind.BARO]),
    "step_buffer.MAG": (step_buffer.MAG, [Kind.MAG]),
    "step_buffer.GNSS": (step_buffer.GNSS, [Kind.GNSS]),
    "step_buffer.SETPOINT": (step_buffer.SETPOINT, [Kind.SETPOINT]),
    "hil_pwm._PWM": (hil_pwm._PWM, [Kind.PWM]),
    **{f"hil_codec._S_{k.name}": (getattr(hil_codec, f"_S_{k.name}"), [k])
       for k in DTYPES if k not in (Kind.PWM, Kind.FAULT)},
    "hil_fault._FAULT": (hil_fault._FAULT, [Kind.FAULT]),
    "ardupilot physics._PWM": (ardupilot_physics._PWM, [Kind.PWM]),
    **{f"record_struct({k.name})": (record_struct(k), [k]) for k in DTYPES},
}

# Partial readers: every value they read must be a C field element of the right type.
PARTIAL = {
    "record_structs.KIND": (record_structs.KIND, Kind.IMU),
    **{f"record_structs.{k.name}": (getattr(record_structs, k.name), k)
       for k in (Kind.IMU, Kind.BARO, Kind.MAG, Kind.GNSS, Kind.GT_ATT, Kind.GT_NAV)},
    "hil_pwm._SIM_NS": (hil_pwm._SIM_NS, Kind.PWM),
}


@pytest.mark.parametrize("name", WHOLE_SLOTS)
def test_whole_slot_structs_pack_every_c_field_at_its_offset(c_layout, name):
    s, kinds = WHOLE_SLOTS[name]
    assert s.size == len(kinds) * RECORD_SIZE
    want = [e for i, k in enumerate(kinds) for e in _c_elements(c_layout, k, i * RECORD_SIZE)]
    assert _struct_elements(s) == want


@pytest.mark.parametrize("name", PARTIAL)
def test_field_readers_read_c_fields_of_their_type(c_layout, name):
    s, kind = PARTIAL[name]
    got = _struct_elements(s)
    assert got and set(got) <= set(_c_elements(c_layout, kind)), got


def test_field_readers_read_their_fields_in_slot_order():
    dt = DTYPES[Kind.GNSS]
    s = record_struct(Kind.GNSS, ["lon_e7", "fix_type"])
    rec = np.zeros(1, dt)
    rec["lon_e7"], rec["fix_type"], rec["lat_e7"] = -7, 3, 99
    assert s.unpack_from(rec.tobytes()) == (-7, 3)
    with pytest.raises(ValueError):
        record_struct(Kind.GNSS, ["fix_type", "lon_e7"])
    with pytest.raises(ValueError):
        record_struct(Kind.GNSS, ["no_such_field"])


def test_flags_offset_header_size_and_word_index_agree_with_c(c_layout):
    c = _c_fields(c_layout)
    assert FLAGS_OFFSET == c["h.flags"][0]
    assert HEADER_SIZE == min(off for p, (off, *_) in c.items() if p.startswith("u."))
    for kind, member in UNION_MEMBER.items():
        for path, (off, *_) in c.items():
            if not (path.startswith("h.") or path.startswith(f"u.{member}.")):
                continue
            field = path.rsplit(".", 1)[1]
            for itemsize in (2, 4, 8):
                if off % itemsize == 0:
                    assert word_index(kind, field, itemsize) * itemsize == off, (kind, field)
                else:
                    with pytest.raises(ValueError):
                        word_index(kind, field, itemsize)
    assert word_index(Kind.NONE, "sim_ns", 8) * 8 == c["h.sim_ns"][0]


def test_step_buffer_word_writes_land_on_the_imu_fields():
    buf = step_buffer.StepBuffer(8)
    buf.write_imu_headers(3, 0xFFFFFFFE, np.array([10, 20, 30], dtype=np.int64))
    buf.imu_payload(3)[:] = np.arange(21, dtype=np.float32).reshape(3, 7)
    recs = buf.finish(3).view(IMU_DTYPE)
    assert recs["kind"].tolist() == [int(Kind.IMU)] * 3
    assert recs["flags"].tolist() == [0, 0, FLAG_STEP_END]
    assert recs["seq"].tolist() == [0xFFFFFFFE, 0xFFFFFFFF, 0]
    assert recs["sim_ns"].tolist() == [10, 20, 30] and recs["wall_ns"].tolist() == [0] * 3
    assert recs["sample_index"].tolist() == [0, 1, 2]
    assert recs["samples_per_step"].tolist() == [3] * 3
    assert recs["accel_frd_m_s2"][1].tolist() == [7, 8, 9]
    assert recs["gyro_frd_rad_s"][1].tolist() == [10, 11, 12]
    assert recs["temperature_c"].tolist() == [6, 13, 20] and recs["reserved"].tolist() == [0] * 3
