"""The C core is portable flight-controller code.

- Cross-compiles for a Cortex-M4F (arm-none-eabi-gcc, hard float, -Werror) and
  references no heap, no stdio and no double-precision software routines
  (the M4F FPU is single precision: a stray double would be emulated).
- Has no writable globals (nm shows no data/bss symbols).
- Compiles on the host with strict warnings, -Wconversion and -Wdouble-promotion.
- Includes only its own headers and the C standard headers it needs.
"""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

import silbridge.fc_sil as fc_pkg

CORE = Path(fc_pkg.__file__).resolve().parent / "core"
SOURCES = sorted(CORE.glob("*.c"))
ARM_FLAGS = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-std=c11",
             "-O2", "-Wall", "-Wextra", "-Werror", "-Wdouble-promotion", "-Wconversion",
             "-Wshadow"]
HOST_FLAGS = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-Wpedantic", "-Wconversion",
              "-Wdouble-promotion", "-Wshadow", "-Wstrict-prototypes", "-Wmissing-prototypes",
              "-Wcast-qual", "-Wundef"]
FORBIDDEN = re.compile(r"^(malloc|calloc|realloc|free|printf|fprintf|sprintf|snprintf|puts|"
                       r"putchar|fopen|fwrite|abort|exit|time|clock|clock_gettime|"
                       r"__aeabi_d\w+)$")
# string.h for memcpy only: fill_status copies the control law's report in one piece, and
# the Cortex-M4F check already admits memcpy/memset among its external symbols.
STD_HEADERS = {"math.h", "stdbool.h", "stdint.h", "stddef.h", "string.h"}


def compile_all(cc, flags, out_dir):
    objs = []
    for src in SOURCES:
        obj = out_dir / (src.stem + ".o")
        proc = subprocess.run([cc, *flags, "-I", str(CORE), "-c", str(src), "-o", str(obj)],
                              capture_output=True, text=True)
        assert proc.returncode == 0, f"{src.name}:\n{proc.stderr}"
        objs.append(obj)
    return objs


def nm_symbols(nm, objs):
    out = subprocess.run([nm, *map(str, objs)], capture_output=True, text=True, check=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and not line.endswith(":"):
            syms.append((parts[-2], parts[-1]))
    return syms


def test_cortex_m4f_build_has_no_heap_stdio_or_double(tmp_path):
    cc = shutil.which("arm-none-eabi-gcc")
    if cc is None:
        pytest.skip("arm-none-eabi-gcc not installed: run tools/install_sysdeps.sh "
                    "(Debian: gcc-arm-none-eabi libnewlib-arm-none-eabi) to run this check")
    objs = compile_all(cc, ARM_FLAGS, tmp_path)
    nm = shutil.which("arm-none-eabi-nm") or "nm"
    syms = nm_symbols(nm, objs)
    undefined = sorted({name for typ, name in syms if typ == "U"})
    bad = [s for s in undefined if FORBIDDEN.match(s)]
    assert not bad, f"the core references {bad}"
    own = {src.stem for src in SOURCES}
    external = [s for s in undefined if not s.startswith("fc_")]
    # What remains: single-precision libm and compiler helpers (int64 maths).
    assert all(s.endswith("f") or s.startswith("__aeabi_l") or s in ("memcpy", "memset")
               for s in external), external
    assert own


def test_no_writable_globals(tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no host C compiler")
    # -fno-pic: with PIC, const tables holding pointers land in .data.rel.ro (shown as D)
    objs = compile_all(cc, ["-std=c11", "-O2", "-fno-common", "-fno-pic"], tmp_path)
    writable = [(t, n) for t, n in nm_symbols("nm", objs) if t in "BbDdCGgSs"]
    assert not writable, f"writable data in the core: {writable}"


def test_host_build_is_clean_with_strict_warnings(tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no host C compiler")
    compile_all(cc, HOST_FLAGS, tmp_path)


def test_core_includes_only_its_headers_and_the_standard_library():
    for path in list(CORE.glob("*.c")) + list(CORE.glob("*.h")):
        for inc in re.findall(r'#include\s+[<"]([^>"]+)[>"]', path.read_text()):
            assert inc in STD_HEADERS or (inc.startswith("fc_") and (CORE / inc).exists()), \
                f"{path.name} includes {inc}"
