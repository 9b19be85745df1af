"""Fixtures for the shared-memory tests: unique instance names, cleaned up
whatever a test leaves behind, and the helper-process launcher."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from silbridge.shm.errors import shm_path

# The cffi bindings of the hand-off's choice (handoff_cffi.py), imported by name
# (--import-mode=importlib), as tests/fc_sil does with its block bindings.
if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))

PEER = Path(__file__).with_name("peer_proc.py")
_counter = itertools.count()


@pytest.fixture
def name():
    """A fresh instance name; its /dev/shm object is removed after the test."""
    n = f"t{os.getpid()}-{next(_counter)}"
    yield n
    try:
        os.unlink(shm_path(n))
    except FileNotFoundError:
        pass


class Helpers:
    """Starts tests/shm/peer_proc.py processes and kills any left at teardown."""

    def __init__(self):
        self.procs: list[subprocess.Popen] = []

    def spawn(self, *args: str) -> subprocess.Popen:
        """Start the helper with args; its stdout is JSON lines."""
        proc = subprocess.Popen([sys.executable, str(PEER), *args], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        self.procs.append(proc)
        return proc

    @staticmethod
    def finish(proc: subprocess.Popen, timeout_s: float = 60.0) -> dict:
        """Wait for a helper, fail with its stderr if it failed, return its last JSON line."""
        out, err = proc.communicate(timeout=timeout_s)
        assert proc.returncode == 0, f"helper failed ({proc.returncode}): {err}"
        return json.loads(out.strip().splitlines()[-1])

    @staticmethod
    def read_line(proc: subprocess.Popen) -> dict:
        """The helper's next JSON line (it prints one at each milestone)."""
        line = proc.stdout.readline()
        if not line:
            proc.wait(5)
            pytest.fail(f"helper ended early ({proc.returncode}): {proc.stderr.read()}")
        return json.loads(line)

    def cleanup(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                proc.kill()
            proc.wait(10)
            for f in (proc.stdout, proc.stderr):
                if f:
                    f.close()


@pytest.fixture
def helpers():
    h = Helpers()
    yield h
    h.cleanup()
