"""`fly`'s error RMS names its window, and it is not `analyze`'s figure (issue 22: both
printed "attitude RMS", fly over 10 s to the end, analyze over 30-120 s: one label, two
numbers)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

SB = [sys.executable, "-m", "silbridge.tools"]


def test_fly_labels_its_window_and_analyze_names_its_own(tmp_path):
    log = tmp_path / "run.mcap"
    fly = subprocess.run(SB + ["fly", "--processes", "1", "--duration", "8", "--log", str(log),
                               "--viz-hz", "0"], capture_output=True, text=True, timeout=300)
    assert fly.returncode == 0, fly.stderr
    m = re.search(r"^error RMS over ([\d.]+)-([\d.]+) s \(whole run after settling\): "
                  r"attitude ([\d.]+) deg", fly.stdout, re.M)
    assert m, fly.stdout
    # S1 at 8 s: settled after half the run (at most 10 s), to the end
    assert (float(m.group(1)), float(m.group(2))) == (4.0, 8.0)
    assert "attitude RMS" not in fly.stdout and "attitude error RMS" not in fly.stdout

    js = subprocess.run(SB + ["fly", "--processes", "1", "--duration", "8", "--json"],
                        capture_output=True, text=True, timeout=300)
    s = json.loads(js.stdout)
    assert s["rms_window_s"] == [4.0, 8.0]
    assert f"{s['attitude_rms_deg']:.3f}" == m.group(3)

    an = subprocess.run(SB + ["analyze", str(log)], capture_output=True, text=True,
                        timeout=300)
    assert an.returncode == 0, an.stderr
    window = re.search(r"analysis window ([\d.]+)-([\d.]+) s", an.stdout)
    assert window, an.stdout
    assert "attitude error RMS" in an.stdout and "error RMS over" not in an.stdout
