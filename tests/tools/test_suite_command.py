"""`bench --suite nav` and `--suite failures` read bench's options the same way
(tools/benchmark/suite_command.py): the paper suite's options and impossible values are refused
before any run, with a message that says what to do, and nothing is written."""

import subprocess
import sys

import pytest


def _bench(tmp_path, *args):
    return subprocess.run([sys.executable, "-m", "silbridge.tools", "bench", "--fc", "ours",
                           "--out", str(tmp_path / "out"), *args],
                          capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("suite", ["nav", "failures"])
def test_paper_options_are_refused_not_ignored(tmp_path, suite):
    r = _bench(tmp_path, "--suite", suite, "--duration", "30")
    assert r.returncode == 2, r.stderr
    assert "--duration" in r.stderr and f"--suite {suite} flies its own plans" in r.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("suite", ["nav", "failures"])
def test_zero_runs_and_a_negative_speed_are_refused(tmp_path, suite):
    r = _bench(tmp_path, "--suite", suite, "--runs", "0")
    assert r.returncode == 2 and "--runs must be >= 1" in r.stderr
    r = _bench(tmp_path, "--suite", suite, "--speed", "-1")
    assert r.returncode == 2 and "--speed must be > 0" in r.stderr
    assert not (tmp_path / "out").exists()


def test_an_unknown_plan_is_refused(tmp_path):
    r = _bench(tmp_path, "--suite", "failures", "--scenarios", "F1,F99")
    assert r.returncode == 2 and "F99" in r.stderr
