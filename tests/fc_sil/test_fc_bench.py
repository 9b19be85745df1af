"""`silbridge fc-bench` runs and reports its keys (figures only, no timing asserts)."""

import json
import subprocess
import sys


def test_fc_bench_json_keys():
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "fc-bench", "--json",
                          "--samples", "5000", "--repeat", "1"],
                         capture_output=True, text=True, check=True).stdout
    res = json.loads(out.strip().splitlines()[-1])
    for key in ("imu_step_ns", "pwm_step_ns", "batch_step_ns", "batch_samples_per_s"):
        assert res[key] > 0, key
    assert res["samples"] == 5000
