"""`python -m silbridge.tools.autopilots.ardupilot.speed`: the same ArduCopter binary on its own
physics and on ours, side by side. The figures depend on the machine: only that both are measured and
reported (and the per-packet profile) is checked, never a speed."""

import json
import math
import os
import subprocess
import sys

import shutil
from pathlib import Path

import pytest

SPEED = "silbridge.tools.autopilots.ardupilot.speed"   # run as python -m
needs_binary = pytest.mark.skipif(
    not os.environ.get("SILBRIDGE_ARDUCOPTER"),
    reason="set SILBRIDGE_ARDUCOPTER to an arducopter SITL binary to compare its speeds "
           "(none on this machine; see docs/tutorials/arducopter-and-px4.md)")


@needs_binary
def test_speed_tool_prints_both_speeds_and_the_ratio():
    p = subprocess.run([sys.executable, "-m", SPEED, "--skip", "2", "--span", "3",
                        "--flight", "0", "--json"],
                       capture_output=True, text=True, timeout=150)
    assert p.returncode == 0, p.stderr[-2000:]
    out = json.loads(p.stdout)
    ref, ours = out["reference"]["realtime_factor"], out["json_idle"]["realtime_factor"]
    assert ref > 0 and ours > 0 and math.isfinite(out["ratio_json_idle"])
    assert out["ratio_json_idle"] == pytest.approx(ours / ref)
    assert out["json_idle"]["packets"] >= 2900          # 3 s at 1 kHz, one per frame
    assert out["json_floor"]["realtime_factor"] > 0 and math.isfinite(out["ratio_json_floor"])
    for key in ("ours_us", "ours_step_us", "sitl_us"):
        assert out["json_idle"][key]["median"] > 0


def _env_without_sitl() -> dict:
    """This environment with no arducopter to find: the variable removed, PATH cut to the
    interpreter's folder and the system's (as the PX4 twin in test_px4_protocol.py does)."""
    env = dict(os.environ)
    env.pop("SILBRIDGE_ARDUCOPTER", None)
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    return env


def test_speed_tool_without_a_binary_says_how_to_get_one(tmp_path):
    # Runs everywhere, binary or not: the variable is removed in the subprocess only.
    env = _env_without_sitl()
    if shutil.which("arducopter", path=env["PATH"]):
        pytest.skip("an arducopter binary is in /usr/bin here: no binary cannot be shown")
    p = subprocess.run([sys.executable, "-m", SPEED, "--json"],
                       capture_output=True, text=True, timeout=60, env=env)
    assert p.returncode == 2, p.stderr
    assert "SILBRIDGE_ARDUCOPTER" in p.stderr and "waf copter" in p.stderr
    assert "Traceback" not in p.stderr and p.stdout == ""
    # A variable naming a file that is not there is the same user error.
    env["SILBRIDGE_ARDUCOPTER"] = str(tmp_path / "missing")
    p = subprocess.run([sys.executable, "-m", SPEED, "--json"],
                       capture_output=True, text=True, timeout=60, env=env)
    assert p.returncode == 2 and "waf copter" in p.stderr and "Traceback" not in p.stderr
