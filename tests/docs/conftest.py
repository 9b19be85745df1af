"""Fixtures of the docs tests, each made once per session and shared:

- `tiny_bench`: a real campaign as small as it gets (S1, one run of 20 s simulated, its
  windows moved inside those 20 s) and a one-step transport comparison (shared memory at
  1 kHz), in the folder layout `make bench` leaves (bench-out/, bench-out/transport/): the
  results page is written from it and its HTML report is opened in the browser;
- `docs_site`: `mkdocs build --strict` of the repository into a temporary folder, the
  build's outcome kept for test_docs_build.py and the site for test_browser.py.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
CLI = [sys.executable, "-m", "silbridge"]

TINY_BENCH = ["--scenarios", "S1", "--runs", "1", "--duration", "20", "--jobs", "1",
              "--warmup", "0", "5", "--transient", "5", "10", "--analysis", "10", "20",
              "--yaw-window", "15", "20"]


def _transport_seconds_flag() -> str:
    """The transport's per-rate wall-time flag: `--seconds-per-rate` in the one flag
    vocabulary (tools/cli/cmd_transport.py), `--duration` before it."""
    from silbridge.tools.cli.cli import build_parser
    parser = build_parser({"transport": "cmd_transport"})
    sub = next(a for a in parser._actions if a.dest == "command")
    flags = {s for a in sub.choices["transport"]._actions for s in a.option_strings}
    return "--seconds-per-rate" if "--seconds-per-rate" in flags else "--duration"


def _run(argv: list[str], what: str) -> None:
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"{what} failed:\n{done.stderr[-3000:]}"


@pytest.fixture(scope="session")
def tiny_bench_args() -> list[str]:
    return list(TINY_BENCH)


@pytest.fixture(scope="session")
def tiny_bench(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("docs") / "bench-out"
    _run(CLI + ["bench", "--out", str(out), *TINY_BENCH], "the tiny campaign")
    _run(CLI + ["transport", "--out", str(out / "transport"), "--transports", "shm",
                "--imu-max", "1000", _transport_seconds_flag(), "1"], "the tiny transport run")
    return out


@dataclass
class SiteBuild:
    returncode: int
    output: str
    site: Path


def mkdocs_missing() -> str | None:
    """Why the site cannot be built here, or None."""
    for module, dist in (("mkdocs", "mkdocs"), ("material", "mkdocs-material")):
        if importlib.util.find_spec(module) is None:
            return (f"{dist} is not installed in this environment: install the test extras "
                    f"(pip install -e '.[test]') to build the docs")
    return None


@pytest.fixture(scope="session")
def docs_site(tmp_path_factory) -> SiteBuild:
    reason = mkdocs_missing()
    if reason:
        pytest.skip(reason)
    site = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(site), "--config-file", str(REPO_ROOT / "mkdocs.yml")],
                          cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    return SiteBuild(done.returncode, done.stdout + done.stderr, site)
