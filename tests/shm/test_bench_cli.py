"""`silbridge shm-bench --json` runs its two processes and prints every key
the issue names (figures only: nothing here judges speed)."""

from __future__ import annotations

import json
import subprocess
import sys


def test_shm_bench_json_has_every_figure():
    proc = subprocess.run([sys.executable, "-m", "silbridge.tools", "shm-bench", "--seconds",
                           "0.05", "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    res = json.loads(proc.stdout)
    for key in ("stream_records_per_s", "batch_records_per_s", "pingpong_round_trips_per_s",
                "c_stream_records_per_s", "c_pingpong_round_trips_per_s"):
        assert res[key] > 0, key
    assert set(res["rtt_ns"]) == {"p50", "p99"}
    assert set(res["one_way_ns"]) == {"p50", "p99", "max"}
    assert res["one_way_ns"]["p50"] > 0
    assert res["overwritten"] == 0 and res["errors"] == 0
