"""`silbridge bridge --param/--feature-off/--params` act on our FC, and are refused where they
cannot act (ArduPilot, PX4); every other option the foreign links cannot honour is refused too
(issue 22: they used to be accepted and dropped)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

SB = [sys.executable, "-m", "silbridge.tools"]
GAIN = "ATC_RAT_RLL_P=0.3"          # default 0.135; S1 leaves the ground at 5 s
SECONDS = "8"


def _fly_hash(*extra) -> str:
    p = subprocess.run(SB + ["fly", "--processes", "1", "--duration", SECONDS, "--json", *extra],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout)["trace_hash"]


def _bridge_and_fc(name: str, bridge_extra, fc_extra=()) -> tuple[dict, str]:
    bridge = subprocess.Popen(SB + ["bridge", "--instance", name, "--duration", SECONDS,
                                    "--json", *bridge_extra],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    fc = subprocess.Popen(SB + ["fc", "--instance", name, "--json", *fc_extra],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        out, err = bridge.communicate(timeout=300)
        _, fc_err = fc.communicate(timeout=60)
    finally:
        for p in (bridge, fc):
            if p.poll() is None:
                p.kill()
                p.wait()
    assert bridge.returncode == 0 and fc.returncode == 0, err[-2000:] + fc_err[-2000:]
    return json.loads(out.strip().splitlines()[-1]), fc_err


def test_bridge_params_reach_our_fc(tmp_path):
    parm = tmp_path / "tuned.parm"
    parm.write_text("ATC_RAT_PIT_P 0.2\n")
    extra = ["--param", GAIN, "--feature-off", "d_filter", "--params", str(parm)]
    want = _fly_hash(*extra)
    assert want != _fly_hash()
    summary, fc_err = _bridge_and_fc(f"handover-{os.getpid()}", extra)
    assert summary["trace_hash"] == want
    assert "from the bridge: --param ATC_RAT_RLL_P=0.3 --feature-off d_filter" in fc_err


def test_the_fc_command_line_wins_over_the_bridge():
    want = _fly_hash("--param", "ATC_RAT_RLL_P=0.25")
    summary, _ = _bridge_and_fc(f"handover-win-{os.getpid()}", ["--param", GAIN],
                                ["--param", "ATC_RAT_RLL_P=0.25"])
    assert summary["trace_hash"] == want


@pytest.mark.parametrize("fc", ["ardupilot", "px4"])
@pytest.mark.parametrize("extra, says", [
    (["--param", GAIN], "keeps its own"),
    (["--feature-off", "d_filter"], "keeps its own"),
    (["--transport", "udp"], "--transport"),
    (["--busy-wait"], "--busy-wait"),
])
def test_foreign_autopilots_refuse_our_fc_options(fc, extra, says):
    p = subprocess.run(SB + ["bridge", "--fc", fc, *extra], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2, p.stderr
    assert says in p.stderr and f"--fc {fc}" in p.stderr and "Traceback" not in p.stderr


def test_ardupilot_refuses_real_time():
    p = subprocess.run(SB + ["bridge", "--fc", "ardupilot", "--speed", "2"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "SITL paces the JSON link" in p.stderr
