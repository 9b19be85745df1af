"""A command that needs an autopilot binary stops, before any run, when there is none.

`bench --fc ardupilot|px4` (alone or beside ours) and `tune anchor`: no binary (no flag,
no SILBRIDGE_ARDUCOPTER / SILBRIDGE_PX4, none on PATH) or a path that is not an executable
is one line saying how to build one, exit status 2, and nothing written. These run
whether or not CI points the variables at real binaries: each subprocess gets its own
environment, with the variable unset or pointing at a path that does not exist.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

CLI = [sys.executable, "-m", "silbridge.tools"]
ENV = {"ardupilot": "SILBRIDGE_ARDUCOPTER", "px4": "SILBRIDGE_PX4"}
COMMAND = {"ardupilot": "arducopter", "px4": "px4"}
FLAG = {"ardupilot": "--arducopter", "px4": "--px4"}
BUILD = {"ardupilot": "./waf copter", "px4": "make px4_sitl_default"}


def _env(tmp_path, fc: str, value: str | None) -> dict:
    """The environment with the autopilot's variable unset (value None) or set, and a PATH
    that holds our Python but no autopilot."""
    env = dict(os.environ)
    env.pop(ENV[fc], None)
    if value is not None:
        env[ENV[fc]] = value
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    if shutil.which(COMMAND[fc], path=env["PATH"]):
        pytest.skip(f"`{COMMAND[fc]}` is installed in /usr/bin here: no binary cannot be shown")
    return env


def _bench(tmp_path, fc_list: str, env: dict, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(CLI + ["bench", "--fc", fc_list, "--scenarios", "S1", "--runs", "1",
                                 "--duration", "4", "--jobs", "1", "--no-report", "--out",
                                 str(tmp_path / "out"), *extra],
                          capture_output=True, text=True, env=env, timeout=120)


@pytest.mark.parametrize("fc", ["ardupilot", "px4"])
@pytest.mark.parametrize("alone", [True, False], ids=["alone", "beside-ours"])
def test_bench_without_the_binary_stops_before_any_run(tmp_path, fc, alone):
    p = _bench(tmp_path, fc if alone else f"ours,{fc}", _env(tmp_path, fc, None))
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr and p.stdout == ""
    # The hint: every way to give the binary, and how to build one.
    assert FLAG[fc] in p.stderr and ENV[fc] in p.stderr and BUILD[fc] in p.stderr
    assert not (tmp_path / "out").exists()     # not even our FC's runs: no column dropped


@pytest.mark.parametrize("fc", ["ardupilot", "px4"])
def test_bench_with_a_variable_pointing_nowhere_is_an_error(tmp_path, fc):
    missing = str(tmp_path / "no" / COMMAND[fc])
    p = _bench(tmp_path, f"ours,{fc}", _env(tmp_path, fc, missing))
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert missing in p.stderr and BUILD[fc] in p.stderr
    assert not (tmp_path / "out").exists()


def test_bench_with_a_file_that_is_not_executable_is_an_error(tmp_path):
    not_exe = tmp_path / "arducopter"
    not_exe.write_text("not a program\n")
    p = _bench(tmp_path, "ardupilot", _env(tmp_path, "ardupilot", None),
               "--arducopter", str(not_exe))
    assert p.returncode == 2 and "not executable" in p.stderr and "./waf copter" in p.stderr


def test_the_old_sitl_flag_still_names_the_binary_and_says_it_is_deprecated(tmp_path):
    missing = str(tmp_path / "old-spelling" / "arducopter")
    p = _bench(tmp_path, "ardupilot", _env(tmp_path, "ardupilot", None), "--sitl", missing)
    assert p.returncode == 2
    assert "--sitl is deprecated, use --arducopter" in p.stderr and missing in p.stderr


def test_a_binary_for_a_controller_not_flown_is_refused(tmp_path):
    p = _bench(tmp_path, "ours", _env(tmp_path, "px4", None), "--px4", sys.executable)
    assert p.returncode == 2 and "--px4 is for --fc px4" in p.stderr
    p = _bench(tmp_path, "ours", _env(tmp_path, "ardupilot", None), "--speed", "10")
    assert p.returncode == 2 and "--speed is for --fc ardupilot" in p.stderr
    assert not (tmp_path / "out").exists()


def test_tune_anchor_without_arducopter_stops_before_flying(tmp_path):
    pytest.importorskip("scipy")        # `tune` checks its extra first
    out = tmp_path / "anchor"
    for value in (None, str(tmp_path / "missing" / "arducopter")):
        p = subprocess.run(CLI + ["tune", "anchor", "--axis", "roll", "--out", str(out)],
                           capture_output=True, text=True, timeout=120,
                           env=_env(tmp_path, "ardupilot", value))
        assert p.returncode == 2, p.stderr
        assert "Traceback" not in p.stderr and "./waf copter" in p.stderr
        assert not out.exists()
