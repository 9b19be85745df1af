"""`silbridge speed`: one real run of every case (bare JSBSim, both lockstep modes with and
without a log), its figures and ratios derived from the runs it reports, ArduCopter skipped
with a line saying why when no binary is at hand. Speeds depend on the machine: no figure's
size is checked, only that the figures agree with each other."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from silbridge.tools.cli.cmd_speed import print_report

SB = [sys.executable, "-m", "silbridge"]
CASES = ["jsbsim", "fly1", "fly2", "fly1_log", "fly2_log", "campaign1", "campaign2"]


def _env_without_arducopter() -> dict:
    env = dict(os.environ)
    env.pop("SILBRIDGE_ARDUCOPTER", None)
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    return env


@pytest.fixture(scope="module")
def result() -> dict:
    env = _env_without_arducopter()
    if shutil.which("arducopter", path=env["PATH"]):
        pytest.skip("an arducopter binary is in /usr/bin here: its skip cannot be shown")
    done = subprocess.run(SB + ["speed", "--runs", "1", "--duration", "1", "--campaign", "1",
                                "--json"],
                          capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout)


def test_every_case_runs_once_and_arducopter_is_skipped_with_a_reason(result):
    assert result["order"] == CASES and sorted(result["cases"]) == sorted(CASES)
    assert result["runs"] == 1 and result["duration_s"] == 1
    assert "SILBRIDGE_ARDUCOPTER" in result["skipped"]["arducopter"]
    for name, c in result["cases"].items():
        assert len(c["runs"]) == 1, name
        x = c["realtime_factor"]
        assert x["min"] == x["median"] == x["max"] == c["runs"][0]["realtime_factor"] > 0
        assert c["worst_below_median"] == 0.0
        assert c["of_arducopter"] is None


def test_ratios_and_per_step_times_follow_from_the_runs(result):
    hz = result["physics_hz"]
    bare = result["cases"]["jsbsim"]["realtime_factor"]["median"]
    for name, c in result["cases"].items():
        x = c["realtime_factor"]["median"]
        assert c["of_jsbsim"] == pytest.approx(x / bare), name
        assert c["wall_us_per_step"]["median"] * x * hz == pytest.approx(1e6), name
        r = c["runs"][0]
        if name == "jsbsim" or name.startswith("campaign"):
            assert c["loop_cpu_s"] is None and c["cpu_us_per_step"] is None
        else:
            # The flight's own --json figures, passed through and divided by its steps.
            assert r["sim_s"] == pytest.approx(1.0) and r["loop_cpu_s"] > 0
            assert c["loop_cpu_s"]["median"] == r["loop_cpu_s"]
            assert c["cpu_us_per_step"]["median"] == pytest.approx(
                1e6 * r["loop_cpu_s"] / (r["sim_s"] * hz))


def test_the_issues_targets_sit_beside_the_measured_ratios(result):
    got = {(t["case"], t["figure"]): t for t in result["targets"]}
    assert set(got) == {("fly1", "of_jsbsim"), ("fly2", "of_jsbsim"),
                        ("fly2", "worst_below_median"), ("campaign2", "of_single_run")}
    assert got["campaign2", "of_single_run"]["target"] == 1.6
    assert got["fly1", "of_jsbsim"]["target"] == 0.8
    assert got["fly2", "of_jsbsim"]["target"] == 0.7
    assert got["fly2", "worst_below_median"]["target"] == 0.2
    for (case, figure), t in got.items():
        assert t["measured"] == result["cases"][case][figure]
        assert t["met"] == (t["measured"] >= t["target"] if t["op"] == ">="
                            else t["measured"] <= t["target"])


def test_the_table_has_a_row_per_case_the_skip_and_the_targets(result):
    lines: list[str] = []
    print_report(result, out=lines.append)
    text = "\n".join(lines)
    for name in CASES:
        assert any(line.startswith(result["cases"][name]["label"]) for line in lines), name
    assert "arducopter: skipped: no ArduCopter SITL binary" in text
    assert f"{result['cases']['fly1']['of_jsbsim']:.2f} / >= 0.80" in text
    assert "through their Python methods" not in text


def test_a_flight_off_the_c_nodes_is_said_in_the_report(result):
    """Every flight case says how it reached JSBSim's nodes; one that fell back to the
    Python methods (the same values, a slower step) gets a line saying so and why."""
    for name in ("fly1", "fly2", "fly1_log", "fly2_log"):
        assert result["cases"][name]["jsbsim_nodes"] == "c", name
    changed = json.loads(json.dumps(result))
    changed["cases"]["fly2"]["jsbsim_nodes"] = "python: getter p_rad_s: not a bound method"
    lines: list[str] = []
    print_report(changed, out=lines.append)
    assert ("fly --processes 2: JSBSim's nodes through their Python methods (python: getter "
            "p_rad_s: not a bound method)") in lines


def test_a_bad_run_count_is_a_one_line_error():
    done = subprocess.run(SB + ["speed", "--runs", "0"], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2 and "--runs must be at least 1" in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_the_campaign_flies_every_scenario_and_compares_with_its_single_runs(result):
    """--campaign 1: one run of each of S1..S4 on 1 and on 2 jobs; the overall factor is all
    simulated seconds over the wall time, its ratio is over the 1-job runs' own median."""
    assert result["campaign"] == 1
    single = result["cases"]["campaign1"]["runs"][0]["run_realtime_factor"]
    assert single > 0
    for name in ("campaign1", "campaign2"):
        c = result["cases"][name]
        r = c["runs"][0]
        assert r["sim_s"] == pytest.approx(4.0) and r["realtime_factor"] > 0
        assert r["run_realtime_factor"] > 0
        assert c["single_run_x"] == single
        assert c["of_single_run"] == pytest.approx(r["realtime_factor"] / single)
        # the workers' share of time in flight, and each run's time around its flight
        assert 0.0 < c["flying"] == r["flying"] <= 1.0
        assert c["outside_flight_s"] == r["outside_flight_s"] > 0.0
    lines: list[str] = []
    print_report(result, out=lines.append)
    assert any("x a single run" in line and line.startswith("campaign, 4 runs, --jobs 2")
               and "workers flying" in line and "ms a run outside its flight" in line
               for line in lines)
