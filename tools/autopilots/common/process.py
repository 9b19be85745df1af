"""A foreign autopilot's SITL process: how it is described, found, started and stopped.

Each autopilot's own `sitl.py` (tools/autopilots/ardupilot/, tools/autopilots/px4/)
describes it once as an `Autopilot`: its name in messages, its error, its binary's variable
and command, how to get one, its console log, how an instance is picked and released and
how its process is stopped (both stop with a signal that lets them shut down in order, then
SIGKILL: `stop_process`). What they do alike is here: find the binary (a flag, then the
variable, then PATH), start the process with its console in the working directory, check
that a port is free, read the console's last lines for an error message.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
from dataclasses import dataclass
from typing import Callable

STOP_GRACE_S = 3.0      # wall seconds an autopilot gets to shut down before SIGKILL


@dataclass(frozen=True)
class Autopilot:
    """One foreign autopilot, as the run scaffolding needs to know it."""
    name: str                            # in messages: "ArduCopter", "PX4"
    error: type                          # its user-facing exception
    env: str                             # the variable naming its binary
    command: str                         # its binary's name on PATH
    how_to_get: str                      # the error when there is no binary at all
    build_hint: str                      # "build it with ..." when a given binary is unusable
    log_name: str                        # its console output, in the working directory
    pick: Callable[[], int]              # a free instance number (claimed, where it claims)
    stop: Callable                       # (proc, instance): stop it in order, then SIGKILL
    release: Callable[[int], None] = lambda n: None   # the claim on an instance, ended


def find_binary(autopilot: Autopilot, explicit: str | None) -> str | None:
    """The binary to use, or None: explicit (a flag), then the variable, then PATH."""
    for cand in (explicit, os.environ.get(autopilot.env)):
        if cand:
            if os.path.isfile(cand) and os.access(cand, os.X_OK):
                return os.path.abspath(cand)
            raise autopilot.error(f"{autopilot.name} SITL binary {cand!r} does not exist or is "
                                  f"not executable: build it with {autopilot.build_hint}")
    return shutil.which(autopilot.command)


def require_binary(autopilot: Autopilot, explicit: str | None) -> str:
    """find_binary, or the autopilot's error saying how to get one: for the commands that fly it."""
    binary = find_binary(autopilot, explicit)
    if binary is None:
        raise autopilot.error(autopilot.how_to_get)
    return binary


def port_free(kind: int, port: int) -> bool:
    """Nothing is bound to 127.0.0.1:port (kind: socket.SOCK_STREAM or SOCK_DGRAM)."""
    s = socket.socket(socket.AF_INET, kind)
    try:
        s.bind(("127.0.0.1", port))
        return True
    except OSError:
        return False
    finally:
        s.close()


def spawn(cmd: list, workdir: str, log_name: str, **popen) -> subprocess.Popen:
    """cmd in workdir, its console (stdout and stderr) to workdir/log_name, no stdin."""
    log = open(os.path.join(workdir, log_name), "w")
    try:
        return subprocess.Popen(cmd, cwd=workdir, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, **popen)
    finally:
        log.close()     # the child holds its own descriptor


def stop_process(proc: subprocess.Popen, sig: int = signal.SIGINT,
                 grace_s: float = STOP_GRACE_S) -> None:
    """sig (the autopilot shuts down in order), then SIGKILL after grace_s."""
    if proc.poll() is None:
        try:
            proc.send_signal(sig)
            proc.wait(grace_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def log_tail(path: str, lines: int = 8) -> str:
    """The last lines of a console log in one line, for an error message ("" if none)."""
    try:
        with open(path, errors="replace") as fh:
            return " | ".join(fh.read().strip().splitlines()[-lines:])
    except OSError:
        return ""
