"""The campaign and tool commands' options act, or are refused; their help says the truth.

- ablate: its help shows its own defaults (5 runs, ablate-out), and --no-report acts.
- bench/ablate/tune --params FILE: read-only, missing file refused before any run, the
  file's values reach the flights (the log records them), entries our FC refuses are said.
- transport: --seconds-per-rate (wall seconds per IMU rate); --duration is its hidden,
  deprecated old spelling.
- params export: --out (--output the hidden, deprecated old spelling).
- --ray-address without --executor ray is refused (it would be ignored).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from silbridge.tools.benchmark.run_params import RunParamsError, run_params
from silbridge.tools.cli import cli
from silbridge.tools.logs.mcap_log import read_log

CLI = [sys.executable, "-m", "silbridge.tools"]


def _parser(command: str):
    return cli.build_parser({command: cli.COMMANDS[command]})


def _action(parser, command: str, dest: str):
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    action = next(a for a in sub._actions if a.dest == dest)
    return sub, action


def test_ablate_help_shows_the_defaults_it_runs_with():
    p = _parser("ablate")
    args = p.parse_args(["ablate"])
    assert (args.runs, args.out) == (5, "ablate-out")
    for dest, value in (("runs", "5"), ("out", "ablate-out")):
        sub, action = _action(p, "ablate", dest)
        assert f"(default {value})" in sub._get_formatter()._expand_help(action)
    bench = _parser("bench").parse_args(["bench"])
    assert (bench.runs, bench.out) == (20, "bench-out")   # ablate's defaults are its own


def _ablate(out, *extra) -> dict:
    p = subprocess.run(CLI + ["ablate", "--scenarios", "S1", "--runs", "1", "--duration", "2",
                              "--jobs", "2", "--json", "--out", str(out), *extra],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_ablate_writes_a_report_unless_told_not_to(tmp_path):
    with_report = _ablate(tmp_path / "a")
    index = tmp_path / "a" / "report" / "index.html"
    assert with_report["report"] == str(index) and index.is_file()
    assert "Ablation" in index.read_text()          # the verdicts are on the page
    without = _ablate(tmp_path / "b", "--no-report")
    assert "report" not in without and not (tmp_path / "b" / "report").exists()
    assert (tmp_path / "b" / "ablation.json").is_file()
    # Judged by the paired rule: one seed each is too few pairs for a verdict, and says so.
    assert without["paired"]["no_slew"]["S1"]["pwm_pp_us"]["verdict"] == "too_few"
    assert {r["variant"] for r in without["runs"]} >= {"full", "no_slew", "defaults"}


def test_bench_params_file_reaches_the_flights_and_is_never_written(tmp_path):
    parm = tmp_path / "tuned.parm"
    parm.write_text("ATC_RAT_RLL_D 0.0045\nNOT_A_PARAM 1\n")
    before = parm.read_bytes()
    out = tmp_path / "out"
    p = subprocess.run(CLI + ["bench", "--scenarios", "S1", "--runs", "1", "--duration", "4",
                              "--jobs", "1", "--no-report", "--json", "--out", str(out),
                              "--params", str(parm), "--param", "ATC_RAT_PIT_D=0.005"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "NOT_A_PARAM" in p.stderr and "entry ignored" in p.stderr
    assert json.loads(p.stdout)["params"] == {"ATC_RAT_RLL_D": 0.0045, "ATC_RAT_PIT_D": 0.005}
    log = read_log(str(next((out / "logs" / "full").glob("*.mcap"))))
    flown = log.metadata["params"]
    assert flown["ATC_RAT_RLL_D"] == pytest.approx(0.0045) and \
        flown["ATC_RAT_PIT_D"] == pytest.approx(0.005)
    assert parm.read_bytes() == before


@pytest.mark.parametrize("command", [["bench"], ["ablate"], ["tune", "step"]])
def test_a_missing_params_file_stops_before_any_flight(tmp_path, command):
    if command[0] == "tune":
        pytest.importorskip("scipy")
    out = tmp_path / "out"
    p = subprocess.run(CLI + command + ["--params", str(tmp_path / "nope.parm"),
                                        "--out", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "nope.parm: no such file" in p.stderr, p.stderr
    assert not out.exists() and not (tmp_path / "nope.parm").exists()


def test_our_fc_parameters_for_no_run_of_ours_are_refused(tmp_path):
    # sys.executable stands in for an arducopter binary: refused before it could start.
    p = subprocess.run(CLI + ["bench", "--fc", "ardupilot", "--arducopter", sys.executable,
                              "--param", "ATC_RAT_RLL_D=0.004", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "add ours to --fc" in p.stderr and "--param" in p.stderr


def test_run_params_says_refused_file_entries_and_refuses_bad_overrides(tmp_path):
    parm = tmp_path / "p.parm"
    parm.write_text("ATC_RAT_RLL_D 0.004\nATC_RAT_RLL_P 99\n")
    said = []
    assert run_params(str(parm), ["ATC_RAT_RLL_D=0.005"], say=said.append) == \
        {"ATC_RAT_RLL_D": 0.005}
    assert len(said) == 1 and "ATC_RAT_RLL_P" in said[0]
    with pytest.raises(RunParamsError, match="--param ATC_RAT_PIT_P"):
        run_params(None, ["ATC_RAT_PIT_P=99"])
    with pytest.raises(RunParamsError, match="is a folder"):
        run_params(str(tmp_path), [])


def test_transport_seconds_per_rate_and_its_old_spelling(capsys):
    p = _parser("transport")
    assert p.parse_args(["transport", "--seconds-per-rate", "0.5"]).seconds_per_rate == 0.5
    assert capsys.readouterr().err == ""
    old = p.parse_args(["transport", "--duration", "0.25"])
    assert old.seconds_per_rate == 0.25 and not hasattr(old, "duration")
    assert "--duration is deprecated, use --seconds-per-rate" in capsys.readouterr().err
    sub, _ = _action(p, "transport", "seconds_per_rate")
    assert "--duration" not in sub.format_help()


def test_transport_refuses_a_step_of_no_time():
    p = subprocess.run(CLI + ["transport", "--seconds-per-rate", "0"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "--seconds-per-rate must be > 0" in p.stderr


def test_params_export_out_and_its_old_spelling(tmp_path):
    new, old = tmp_path / "new.parm", tmp_path / "old.parm"
    a = subprocess.run(CLI + ["params", "export", "--out", str(new)],
                       capture_output=True, text=True, timeout=60)
    b = subprocess.run(CLI + ["params", "export", "--output", str(old)],
                       capture_output=True, text=True, timeout=60)
    assert a.returncode == b.returncode == 0 and a.stderr == ""
    assert "--output is deprecated, use --out" in b.stderr
    assert new.read_text() == old.read_text() and "ATC_RAT_RLL_P" in new.read_text()


@pytest.mark.parametrize("command", [["bench"], ["tune", "step"]])
def test_an_executor_option_that_would_be_ignored_is_refused(tmp_path, command):
    if command[0] == "tune":
        pytest.importorskip("scipy")
    p = subprocess.run(CLI + command + ["--ray-address", "auto", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "--ray-address is for --executor ray" in p.stderr
    assert not (tmp_path / "o").exists()
