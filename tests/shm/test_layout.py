"""The Python record views agree with the C structs, field by field.

A tiny C program, generated from the numpy dtypes of silbridge.shm.records
and compiled with `cc` against shm/include/sb_records.h, prints offsetof,
sizeof and the element type of every field of every record kind; each must
equal the dtype's offset, itemsize and base type. The extension's own view
of the segment structs is checked against the static layout too.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from silbridge.shm import _ring, errors
from silbridge.shm.records import DTYPES, RECORD_DTYPE, RECORD_SIZE, RECORDS_VERSION, Kind

INCLUDE = Path(__file__).resolve().parents[2] / "shm" / "include"

# Kind -> member of the payload union in sb_record.
UNION_MEMBER = {
    Kind.IMU: "imu", Kind.BARO: "baro", Kind.MAG: "mag", Kind.GNSS: "gnss",
    Kind.GT_ATT: "gt_att", Kind.GT_NAV: "gt_nav", Kind.PWM: "pwm", Kind.SETPOINT: "setpoint",
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
    assert lay["seg_words"] == 192 and lay["words"] == 8
    assert lay["sizeof_seg_header"] <= lay["header_bytes"] == 4096
    assert lay["records_version"] == RECORDS_VERSION


def test_status_codes_agree_with_the_extension():
    for code in ("E_NAME", "E_CONFIG", "E_MISSING", "E_CREATING", "E_BUSY", "E_STALE",
                 "E_PERM", "E_MAGIC", "E_VERSION", "E_LAYOUT", "E_PEER_BUSY", "E_OS"):
        assert getattr(errors, code) == getattr(_ring, code), code
    assert _ring.SHM_PREFIX == "/" + errors.SHM_PREFIX
