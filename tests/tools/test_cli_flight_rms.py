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


def _summary(**over):
    s = {"scenario": "S1", "seed": 1, "mode": "realtime x1", "processes": 2, "sim_s": 3.3,
         "wall_s": 3.3, "realtime_factor": 1.0,
         "rates_hz": {"imu": 1000.0, "baro": 100.0, "mag": 100.0, "gnss": 10.0, "pwm": 400.0},
         "overwritten": 0, "rejected": 0, "latency_us": {"p50": 5.0, "p99": 9.0},
         "jitter_us": {"p50": 1.0, "p99": 2.0}, "attitude_rms_deg": None,
         "altitude_rms_m": 10.0, "rms_window_s": [10.0, 3.3], "crashed": False,
         "trace_hash": "x", "gcs_flown": False}
    s.update(over)
    return s


def _printed(s) -> str:
    from silbridge.tools.loop.flight import print_summary
    lines = []
    print_summary(s, out=lines.append)
    return "\n".join(lines)


def test_a_run_shorter_than_the_settling_prints_no_error_figure():
    text = _printed(_summary())
    assert "error RMS n/a: the run ended at 3.30 s, before the 10 s settling time" in text
    assert "10-3.3" not in text and "altitude 10.000" not in text


def test_a_gcs_flown_session_prints_no_error_against_the_scenario():
    text = _printed(_summary(sim_s=60.0, rms_window_s=[10.0, 60.0], attitude_rms_deg=0.4,
                             gcs_flown=True))
    assert "error RMS n/a: a ground station flew the vehicle" in text
    assert "altitude 10.000" not in text
