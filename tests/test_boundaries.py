"""The house's boundaries, held by a test (README "Layout").

The two programs meet only through `shm/` and `mavlink/`, so `bridge/` and `fc_sil/` never
import each other; `shm/` imports no other part of the project; `mavlink/` knows records and
messages, not physics or controllers; nothing below the command line imports `tools/` (the
benchmark toolkit and the command line); the portable C core includes only its own headers
and the C standard library, so it compiles on a flight controller as it is. Inside the core,
estimation and control meet only in the vehicle state (`fc_vehicle_state.h`): the control law
reads no estimator and no ground truth directly. The per-block C bindings (`_blocks`, wrapped
by `fc_sil/blocks.py`) are for tests only: no program imports them and the flight's `_core`
carries none of them.
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


BLOCK_BINDINGS = {"blocks", "_blocks"}   # fc_sil/blocks.py and the extension it wraps


def _imports_block_bindings(path: Path) -> bool:
    """Whether a file imports fc_sil.blocks or fc_sil._blocks, in any import form."""
    tree = ast.parse(path.read_text(), filename=str(path))
    in_fc_sil = path.parent.name == "fc_sil"
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            mods = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level == 1 and in_fc_sil:      # from . import blocks / from .blocks import
                base = f"silbridge.fc_sil.{base}".rstrip(".")
            elif node.level >= 2:                  # from ..fc_sil import blocks
                base = f"silbridge.{base}"
            mods = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        if any(m.split(".")[:2] == ["silbridge", "fc_sil"] and len(m.split(".")) > 2
               and m.split(".")[2] in BLOCK_BINDINGS for m in mods):
            return True
    return False


def test_only_tests_use_the_block_bindings():
    bad = []
    for part in PARTS:
        for path in sorted((ROOT / part).rglob("*.py")):
            if path != ROOT / "fc_sil" / "blocks.py" and _imports_block_bindings(path):
                bad.append(str(path.relative_to(ROOT)))
    assert not bad, "test-only block bindings imported by:\n" + "\n".join(bad)


def test_the_flight_core_module_carries_no_block_binding():
    from silbridge.fc_sil import _blocks, _core
    shared = {n for n in dir(_blocks) if not n.startswith("__")} & set(dir(_core))
    assert not shared, f"_core exports block bindings: {sorted(shared)}"


def test_the_block_binding_check_sees_an_import(tmp_path):
    pkg = tmp_path / "fc_sil"
    pkg.mkdir()
    for i, text in enumerate(("from . import _blocks\n", "from .blocks import Mixer\n",
                              "from silbridge.fc_sil import blocks\n",
                              "import silbridge.fc_sil._blocks\n")):
        f = pkg / f"m{i}.py"
        f.write_text(text)
        assert _imports_block_bindings(f), text
    ok = pkg / "ok.py"
    ok.write_text("from . import _core\nfrom silbridge.fc_sil.params import BY_NAME\n")
    assert not _imports_block_bindings(ok)
