"""`make bench` sets up the light install only: no test extras (MAVProxy, Ray, ...) and no
apt install as root; `make test` keeps both (issue 22: a 1.8 GB environment for a benchmark)."""

from __future__ import annotations

import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _dry_run(target: str) -> str:
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    # -B: print every recipe even where the venv already exists; -n: run none of them.
    proc = subprocess.run(["make", "-B", "-n", target], cwd=ROOT, capture_output=True,
                          text=True, timeout=60, check=True)
    return proc.stdout


def test_make_bench_installs_only_the_light_set():
    recipe = _dry_run("bench")
    installs = [line for line in recipe.splitlines() if "pip install" in line and " -e " in line]
    assert installs, recipe
    assert all("[" not in line for line in installs), installs   # no extras
    assert "install_sysdeps" not in recipe and "apt-get" not in recipe
    assert "silbridge bench" in recipe and "silbridge transport" in recipe


def test_make_test_installs_the_test_extras_and_runs_pytest():
    recipe = _dry_run("test")
    assert '-e ".[test]"' in recipe
    assert "install_sysdeps" in recipe and "pytest" in recipe
