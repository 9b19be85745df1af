"""`--duration`: simulated seconds; in real time the default is "until stopped" and `inf` is
accepted; lockstep keeps the scenario's duration and refuses inf (issue 22: a real-time GCS
session ended silently after S1's 120 s, and `--duration inf` overflowed)."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time

import pytest

from silbridge.tools.cli.cli import build_parser

SB = [sys.executable, "-m", "silbridge.tools"]


def _options(*argv):
    from silbridge.tools.cli.flight_args import options_from_args
    command = argv[0]
    args = build_parser({command: f"cmd_{command}"}).parse_args(list(argv))
    if command == "sitl":
        from silbridge.tools.cli.cmd_sitl import options_from_args as sitl_options
        return sitl_options(args)
    return options_from_args(args)


@pytest.mark.parametrize("argv, want", [
    (["fly"], None),                                  # lockstep: the scenario's duration
    (["fly", "--duration", "30"], 30.0),
    (["fly", "--realtime"], math.inf),                # real time: until stopped
    (["fly", "--speed", "4"], math.inf),
    (["fly", "--realtime", "--duration", "inf"], math.inf),
    (["fly", "--speed", "2", "--duration", "45"], 45.0),
    (["bridge", "--realtime"], math.inf),
    (["sitl"], math.inf),
    (["sitl", "--duration", "60"], 60.0),
])
def test_parsed_duration(argv, want):
    assert _options(*argv).duration_s == want


@pytest.mark.parametrize("command", [["fly"], ["fly", "--lockstep"], ["bridge"]])
def test_inf_in_lockstep_is_refused(command):
    p = subprocess.run(SB + [*command, "--duration", "inf"], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2
    assert "--duration inf runs until stopped" in p.stderr and "Traceback" not in p.stderr


@pytest.mark.parametrize("bad", ["0", "-3", "nan", "soon"])
def test_a_duration_that_is_no_duration_is_refused(bad):
    p = subprocess.run(SB + ["fly", "--duration", bad], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2 and "--duration" in p.stderr


def test_real_time_runs_past_the_scenario_until_stopped(tmp_path, pitch_push_scenario):
    """A 2 s scenario flown in real time without --duration is still flying when Ctrl-C
    comes, well past 2 s of sim time; the summary says it was interrupted there."""
    scenario = pitch_push_scenario(tmp_path, "short", "a 2 s flight", seed=3, duration_s=2.0,
                                   step_s=0.5)
    proc = subprocess.Popen(SB + ["fly", "--speed", "8", "--no-mavlink", "--processes", "1",
                                  "--scenario", str(scenario), "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # 10 s of wall time at x8 is 80 s of sim time: the scenario's 2 s would have ended
        # it long before, on its own (exit 0, not interrupted).
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err[-3000:]
    s = json.loads(out)
    assert s["interrupted"] == "SIGINT"
    assert s["sim_s"] > 2 * 2.0


def test_the_stop_request_ends_an_until_stopped_run_without_a_traceback():
    proc = subprocess.Popen(SB + ["fly", "--realtime", "--no-mavlink", "--processes", "2",
                                  "--duration", "inf"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        end = time.monotonic() + 120
        while time.monotonic() < end:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            if line.startswith("check drops"):
                break
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err[-3000:]
    assert "INTERRUPTED by SIGTERM" in out and "Traceback" not in err
