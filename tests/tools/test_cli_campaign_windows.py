"""A campaign's windows always lie inside its runs (tools/benchmark/windows_fit.py).

`bench --duration 30` used to keep the 30-120 s analysis window and print a Table 1 from
one sample. Now the default windows are scaled to a shorter run, with a line saying so;
a window the user gave that the run does not cover is refused, and so is an analysis
window too short for Table 1's statistics (exit 2, before any run).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from silbridge.tools.benchmark.windows_fit import (
    DEFAULTS,
    MIN_ANALYSIS_S,
    PROTOCOL_S,
    WindowError,
    fit_windows,
)

CLI = [sys.executable, "-m", "silbridge.tools"]
NONE_GIVEN = {"warmup": None, "transient": None, "analysis": None, "yaw": None}


def test_default_windows_scale_together_to_a_shorter_run():
    w, note = fit_windows(60.0, NONE_GIVEN)
    assert w.warmup == (0.0, 5.0) and w.transient == (5.0, 15.0)
    assert w.analysis == (15.0, 60.0) and w.yaw == (45.0, 60.0)
    assert "scaled by 0.5" in note and "analysis 15-60 s" in note


def test_default_windows_are_left_alone_for_the_protocol_run_and_longer():
    for duration in (PROTOCOL_S, 2 * PROTOCOL_S):
        w, note = fit_windows(duration, NONE_GIVEN)
        assert w == DEFAULTS and note == ""


def test_a_window_the_user_gave_is_kept_or_refused_never_moved():
    w, note = fit_windows(12.0, {**NONE_GIVEN, "analysis": (5.0, 12.0)})
    assert w.analysis == (5.0, 12.0) and w.yaw == (9.0, 12.0)      # the yaw one scaled
    assert "analysis" not in note and "yaw 9-12 s" in note
    with pytest.raises(WindowError, match="--yaw-window 90 120 ends after the run"):
        fit_windows(30.0, {**NONE_GIVEN, "yaw": (90.0, 120.0)})
    with pytest.raises(WindowError, match="wider --analysis"):
        fit_windows(30.0, {**NONE_GIVEN, "analysis": (10.0, 10.5)})


def test_too_short_a_run_is_refused_with_the_shortest_that_works():
    span = DEFAULTS.analysis[1] - DEFAULTS.analysis[0]
    shortest = MIN_ANALYSIS_S * PROTOCOL_S / span
    fit_windows(shortest, NONE_GIVEN)
    with pytest.raises(WindowError, match=f"give --duration {shortest:.3g} s or more"):
        fit_windows(shortest * 0.9, NONE_GIVEN)


def test_bench_shortens_the_windows_and_says_so(tmp_path):
    p = subprocess.run(CLI + ["bench", "--scenarios", "S1", "--runs", "1", "--duration", "12",
                              "--jobs", "1", "--no-report", "--json", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "bench: --duration 12 s is shorter than the 120 s" in p.stderr
    assert "analysis 3-12 s" in p.stderr
    table = json.loads(p.stdout)
    w = table["windows"]
    assert w["analysis"] == [3.0, 12.0] and w["yaw"] == [9.0, 12.0]
    assert all(0.0 <= a < b <= 12.0 for a, b in w.values())
    s1 = table["scenarios"]["S1"]
    # A window with the take-off in it, many samples: not the one-sample table of old.
    assert s1["pwm_pp_us"]["mean"] > 0.0
    assert s1["att_rms_deg"]["mean"] != s1["att_p95_deg"]["mean"]
    assert json.loads((tmp_path / "table1.json").read_text())["windows"] == w


@pytest.mark.parametrize("command", ["bench", "ablate"])
@pytest.mark.parametrize("flags, says", [
    (["--duration", "1"], "shorter than 1 s"),
    (["--duration", "30", "--analysis", "30", "120"], "--analysis 30 120 ends after the run"),
], ids=["too-short", "window-outside"])
def test_a_window_the_run_does_not_cover_is_refused(tmp_path, command, flags, says):
    out = tmp_path / "out"
    p = subprocess.run(CLI + [command, "--scenarios", "S1", "--runs", "1", *flags,
                              "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and says in p.stderr, p.stderr
    assert "Traceback" not in p.stderr and not out.exists()
