"""The house's boundaries, held by a test (README "Layout").

The two programs meet only through `shm/` and `mavlink/`, so `bridge/` and `fc_sil/` never
import each other; `shm/` imports no other part of the project; `mavlink/` knows records and
messages, not physics or controllers; nothing below the command line imports `tools/` (the
benchmark toolkit and the command line); the portable C core includes only its own headers
and the C standard library, so it compiles on a flight controller as it is. Inside the core,
estimation and control meet only in the vehicle state (`fc_vehicle_state.h`): the control law
reads no estimator and no ground truth directly, and neither it nor the bridge's sensor stage
(`bridge/src/sensor_stage.c`) reaches Python or the FC core object: both stand alone. The per-block C bindings (generated with
cffi from the core's headers by tests/fc_sil/core_cffi.py, wrapped by fc_blocks.py) are for
tests only: no program imports them or cffi, a test extra the light install lacks.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("bridge", "fc_sil", "shm", "mavlink", "tools", "jsbsim_models")

# part -> the project parts it must never import
FORBIDDEN = {
    "bridge": {"fc_sil", "tools"},
    "fc_sil": {"bridge", "tools"},
    "shm": {"bridge", "fc_sil", "mavlink", "tools"},
    "mavlink": {"bridge", "fc_sil", "tools"},
}

C_STANDARD_HEADERS = {
    "assert.h", "complex.h", "ctype.h", "errno.h", "fenv.h", "float.h", "inttypes.h",
    "iso646.h", "limits.h", "math.h", "stdalign.h", "stdarg.h", "stdatomic.h", "stdbool.h",
    "stddef.h", "stdint.h", "stdnoreturn.h", "string.h", "tgmath.h",
}


def _imported_parts(path: Path, part: str) -> set[str]:
    """Project parts a Python file imports (absolute `silbridge.X` or relative `..X`)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found = set()
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level >= 2 and node.module:          # from ..other import x
                names = [f"silbridge.{node.module}"]
            elif node.level == 0 and node.module:
                names = [node.module]
        for name in names:
            bits = name.split(".")
            if len(bits) >= 2 and bits[0] == "silbridge" and bits[1] in PARTS:
                found.add(bits[1])
    return found - {part}


@pytest.mark.parametrize("part", sorted(FORBIDDEN))
def test_python_parts_keep_their_boundaries(part):
    bad = []
    for path in sorted((ROOT / part).rglob("*.py")):
        wrong = _imported_parts(path, part) & FORBIDDEN[part]
        if wrong:
            bad.append(f"{path.relative_to(ROOT)} imports {', '.join(sorted(wrong))}")
    assert not bad, "boundary crossed:\n" + "\n".join(bad)


def test_c_core_includes_only_its_own_headers_and_the_standard_library():
    core = ROOT / "fc_sil" / "core"
    own = {p.name for p in core.iterdir()}
    bad = []
    for path in sorted(core.glob("*.[ch]")):
        for m in re.finditer(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', path.read_text(), re.M):
            kind, header = m.groups()
            ok = header in own if kind == '"' else header in C_STANDARD_HEADERS
            if not ok:
                bad.append(f"{path.name}: #include {kind}{header}")
    assert not bad, "the portable core reaches outside itself:\n" + "\n".join(bad)


# The control law's files, and what they must not reach: the estimators, the front end,
# ground truth and the blend (all of it arrives through fc_vehicle_state_t).
CONTROL_FILES = ("fc_control.c", "fc_control.h", "fc_spool.c", "fc_spool.h")
ESTIMATION = re.compile(r"->\s*(ahrs|ins|alt_est|source|gnss_aid|gnss)\b|\b(fc_mahony|fc_ins|fc_alt_est|"
                        r"fc_state_source|fc_blend|fc_gnss_aid)_\w+")


def _code(text: str) -> str:
    """C text without its comments."""
    return re.sub(r"/\*.*?\*/|//[^\n]*", "", text, flags=re.S)


def test_c_control_law_reads_the_vehicle_state_only():
    core = ROOT / "fc_sil" / "core"
    bad = []
    for name in CONTROL_FILES:
        for m in ESTIMATION.finditer(_code((core / name).read_text())):
            bad.append(f"{name}: {m.group(0)}")
    assert not bad, "the control law reads estimation directly:\n" + "\n".join(bad)
    assert ESTIMATION.search("x = c->ahrs.q_wxyz[0];")   # the scan is not vacuous


def test_the_checker_sees_a_crossing(tmp_path):
    """The import scan is not vacuous: it finds both import forms."""
    f = tmp_path / "x.py"
    f.write_text("from silbridge.fc_sil.params import PARAMS\nfrom ..tools import cli\n")
    assert _imported_parts(f, "bridge") == {"fc_sil", "tools"}


# The block bindings' build and wrappers (tests/fc_sil) and what they need: the test extra.
TEST_ONLY = {"cffi", "pycparser", "core_cffi", "fc_blocks", "cdef_from_headers"}


def _test_only_imports(path: Path) -> set[str]:
    """The test-only modules a file imports, in any absolute import form."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found & TEST_ONLY


def test_only_tests_use_the_block_bindings():
    bad = []
    for part in PARTS:
        for path in sorted((ROOT / part).rglob("*.py")):
            if found := _test_only_imports(path):
                bad.append(f"{path.relative_to(ROOT)}: {sorted(found)}")
    assert not bad, "test-only block bindings imported by:\n" + "\n".join(bad)


def test_the_block_binding_check_sees_an_import(tmp_path):
    for i, text in enumerate(("import cffi\n", "from cffi import FFI\n",
                              "from fc_blocks import Mixer\n", "import core_cffi as c\n")):
        f = tmp_path / f"m{i}.py"
        f.write_text(text)
        assert _test_only_imports(f), text
    ok = tmp_path / "ok.py"
    ok.write_text("from . import _core\nfrom silbridge.fc_sil.params import BY_NAME\n")
    assert not _test_only_imports(ok)


def _include_closure(path: Path, dirs: tuple[Path, ...]) -> set[str]:
    """Every header a C file reaches, through the project headers it includes (by name)."""
    seen: set[str] = set()
    todo = [path]
    while todo:
        text = todo.pop().read_text()
        for m in re.finditer(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', text, re.M):
            name = m.group(1)
            if name in seen:
                continue
            seen.add(name)
            todo += [d / name for d in dirs if (d / name).is_file()][:1]
    return seen


# What the two pure-C blocks that sit where the languages meet may reach: the sensor stage
# (an FDM sample in, records out) and the control law (vehicle state in, mixer inputs out).
# Neither may see Python, the FC core object, parameters, or the shared-memory transport: the
# CPython shim and fc_core own those, as PX4's module owns RateControl's topics.
PURE_BLOCKS = {
    "sensor stage": (ROOT / "bridge" / "src" / "sensor_stage.c",
                     (ROOT / "bridge" / "src", ROOT / "shm" / "include"),
                     {"sensor_stage.h", "sb_records.h", "step_maths.h", "vibration.h",
                      "imu_chip.h", "imu_raw.h", "sensor_faults.h", "battery.h",
                      "gnss_model.h", "lowrate.h"}),
    "control law": (ROOT / "fc_sil" / "core" / "fc_control.c", (ROOT / "fc_sil" / "core",),
                    None),
}
CORE_OBJECT_HEADERS = {"fc_core.h", "fc_params.h", "fc_config_map.h",
                       "fc_sched.h", "fc_core_inputs.h"}


@pytest.mark.parametrize("block", sorted(PURE_BLOCKS))
def test_pure_c_blocks_include_no_python_and_no_core(block):
    src, dirs, only_own = PURE_BLOCKS[block]
    reached = _include_closure(src, dirs)
    project = {h for h in reached if h not in C_STANDARD_HEADERS}
    assert "Python.h" not in reached, f"the {block} includes Python.h"
    assert not project & CORE_OBJECT_HEADERS, f"the {block} includes {project & CORE_OBJECT_HEADERS}"
    if only_own is not None:
        assert project <= only_own, f"the {block} reaches {sorted(project - only_own)}"
    assert src.with_suffix(".h").name in reached    # the scan is not vacuous


def test_the_include_scan_follows_headers(tmp_path):
    (tmp_path / "a.c").write_text('#include "b.h"\n#include <math.h>\n')
    (tmp_path / "b.h").write_text('#include "fc_core.h"\n')
    assert _include_closure(tmp_path / "a.c", (tmp_path,)) == {"b.h", "math.h", "fc_core.h"}
