"""`python -m silbridge.tools.soak.report`: the Markdown figures of a soak's JSON."""

from __future__ import annotations

import json
import subprocess
import sys

from silbridge.tools.soak.verdict import verdict


def _result():
    samples = [{"t_s": 60.0 * i, "procs": {"bridge": {"pid": 1, "rss_kb": 40_960 + 10 * i,
                                                      "fds": 5},
                                           "fc": {"pid": 2, "rss_kb": 61_440, "fds": 8}},
                "log_bytes": 40_000_000 * i, "log_mb_per_min": 40.0,
                "streams_hz": {"ATTITUDE": 10.0, "HEARTBEAT": 1.0}, "clock_lag_ms": 3.0,
                "actions_ok": 12 * i, "actions_failed": 0} for i in range(1, 61)]
    minutes = [{"t_s": 60.0 * i, "late_steps": 120, "late_steps_per_min": 120.0,
                "imu_hz": 990.0, "pwm_hz": 398.0} for i in range(60)]
    return {"total_s": 3600.0, "sample_s": 60.0, "samples": samples, "minutes": minutes,
            "actions": {"ok": {"param_set": 120}, "failed": {}, "failures": []},
            "log_bytes": 2_400_000_000,
            "vehicle_summary": {"rates_hz": {"imu": 999.9, "pwm": 400.0}, "late_steps": 7200,
                                "wall_s": 3601.0},
            **verdict(samples, minutes, 3600.0)}


def test_report_prints_the_figures_table(tmp_path):
    path = tmp_path / "soak.json"
    path.write_text(json.dumps(_result()))
    p = subprocess.run([sys.executable, "-m", "silbridge.tools.soak.report", str(path)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    rows = dict(line.strip("|").split(" | ", 1) for line in p.stdout.splitlines()[2:])
    rows = {k.strip(): v.strip(" |") for k, v in rows.items()}
    assert rows["RSS bridge (start / 5 min / end / peak)"] == "40.0 / 40.0 / 40.6 / 40.6 MB"
    assert rows["open fds fc"] == "8"
    assert rows["log growth (median / max)"] == "40.0 / 40.0 MB/min; 2.40 GB in all"
    assert rows["late steps per minute (median / max)"] == "120 / 120"
    assert rows["verdict"] == "PASS"


def test_report_wants_one_file():
    p = subprocess.run([sys.executable, "-m", "silbridge.tools.soak.report"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "usage" in p.stderr
