"""The scripts in examples/ run as a user would run them: a fresh interpreter, a folder
outside the repository, the installed `silbridge` package, short flights."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def _number_row(out: str, label: str) -> tuple[float, float]:
    m = re.search(rf"^{re.escape(label)}\s+(\S+)\s+(\S+)\s*$", out, re.M)
    assert m, f"no row {label!r} in:\n{out}"
    return float(m.group(1)), float(m.group(2))


def test_fly_and_compare_prints_both_columns(tmp_path):
    proc = subprocess.run([sys.executable, str(EXAMPLES / "fly_and_compare.py"),
                           "--duration", "20"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = proc.stdout
    assert "S1, 20 s simulated per flight" in out and "ATC_RAT_RLL_D=0.004" in out
    base, changed = _number_row(out, "attitude error RMS [deg]")
    assert math.isfinite(base) and math.isfinite(changed) and base > 0
    # The changed gain reaches the FC: the roll axis flies differently.
    roll = _number_row(out, "roll error RMS [deg]")
    assert roll[0] != roll[1]
    # A 20 s flight does not cover the paper's windows: the script says which it used.
    assert "\nnote: " in out


def test_every_example_is_run_by_a_test():
    tested = {"fly_and_compare.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested
