"""`silbridge transport` with a tiny configuration: real processes, real FC, real sockets;
checks the JSON keys the issue fixes, the outputs, and that '-nofastcrc' really runs
pymavlink without fastcrc (per process)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from silbridge.tools.transport.transport_bench import imu_steps


def test_imu_steps_1_2_5():
    assert imu_steps(2_000_000)[:7] == [1000, 2000, 5000, 10_000, 20_000, 50_000, 100_000]
    assert imu_steps(2_000_000)[-1] == 2_000_000
    assert imu_steps(15_000) == [1000, 2000, 5000, 10_000]


def test_tiny_comparison_produces_the_json_keys(tmp_path):
    out_dir = tmp_path / "out"
    cmd = [sys.executable, "-m", "silbridge.tools", "transport", "--transports",
           "shm,tcp,udp-nofastcrc", "--imu-max", "1000", "--duration", "0.5", "--json",
           "--out", str(out_dir)]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 0
    report = json.loads(proc.stdout)
    ts = report["transports"]
    assert set(ts) == {"shm", "tcp", "udp-nofastcrc"}
    for name, t in ts.items():
        for key in ("max_imu_hz", "pwm_hz", "latency_us", "drop_ratio"):
            assert key in t, (name, key)
        assert set(t["latency_us"]) == {"p50", "p95", "p99"}
        assert t["steps"][0]["imu_hz_requested"] == 1000
        assert t["pwm_hz"] > 0
    assert ts["tcp"]["steps"][0]["fastcrc"] is True
    assert ts["udp-nofastcrc"]["steps"][0]["fastcrc"] is False
    for path in report["outputs"].values():
        assert os.path.getsize(path) > 0
    md = (out_dir / "transport.md").read_text()
    assert "15,516" in md and "78,383" in md and "| PWM | 340 | 400 |" in md
