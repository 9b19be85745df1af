"""One place per foreign autopilot: each package knows its own autopilot and the shared base,
never the other autopilot (tools/autopilots/{ardupilot,px4,common}, bridge/autopilots/...).

A PX4 flight that imports ArduPilot's log or flight module (as it once did) couples two
autopilots that share nothing but the base; this scan keeps the shared parts in common/.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = {"ardupilot": "px4", "px4": "ardupilot"}     # package -> the one it must not import


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return out


def _crossings(root: Path, part: str, own: str, other: str) -> list[str]:
    """Imports of `other`'s package from the files of `own`'s, under root/part/autopilots/."""
    bad = set()
    for path in sorted((root / part / "autopilots" / own).glob("*.py")):
        for mod in _imports(path):
            bits = mod.split(".")
            if bits[:3] in (["silbridge", "tools", "autopilots"],
                            ["silbridge", "bridge", "autopilots"]) and bits[3:4] == [other]:
                bad.add(f"{path.relative_to(root)} imports {'.'.join(bits[:4])}")
    return sorted(bad)


def test_each_autopilot_imports_only_itself_and_the_common_base():
    bad = []
    for part in ("tools", "bridge"):
        for own, other in PACKAGES.items():
            bad += _crossings(ROOT, part, own, other)
    for autopilot in PACKAGES:                 # the base knows no autopilot in particular
        bad += _crossings(ROOT, "tools", "common", autopilot)
    assert not bad, "\n".join(bad)
    assert (ROOT / "tools" / "autopilots" / "px4" / "flight.py").is_file()   # the tree is there


def test_the_scan_sees_a_crossing(tmp_path):
    pkg = tmp_path / "tools" / "autopilots" / "px4"
    pkg.mkdir(parents=True)
    (pkg / "flight.py").write_text(
        "from silbridge.tools.autopilots.ardupilot.flight import BenchStepHooks\n"
        "from silbridge.tools.autopilots.common.flight import BenchWiring\n")
    assert _crossings(tmp_path, "tools", "px4", "ardupilot") == [
        "tools/autopilots/px4/flight.py imports silbridge.tools.autopilots.ardupilot"]
