"""Either autopilot behind one interface, so a client test runs against both and both must
answer alike: silbridge (`silbridge fly --speed X`, JSBSim and the SIL FC) and, when
SILBRIDGE_ARDUCOPTER names its binary, the real ArduCopter 4.6 SITL on its own physics
(`--model quad`), each on free loopback ports.

silbridge sends to a UDP port the client listens on (as ArduPilot SITL users run MAVProxy and
MAVSDK); ArduCopter serves MAVLink on TCP 5760 + 10 * instance. ``Autopilot`` gives the URL
each client wants: ``pymavlink_url``, ``mavsdk_url``, ``mavproxy_master``.

ArduCopter starts with a fresh EEPROM (-w) and the SITL accelerometer calibration values of
ArduPilot's copter defaults (without them it refuses to arm: "3D Accel calibration needed").
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time

import pytest

HERE = os.path.dirname(__file__)
sys.path.insert(0, HERE)

from sitl_helpers import SitlVehicle, free_udp_port  # noqa: E402

from silbridge.tools.autopilots.ardupilot.sitl import (  # noqa: E402
    ENV_BINARY, MAVLINK_TCP_BASE, PORT_STRIDE, pick_instance, stop_sitl)

KINDS = ("silbridge", "arducopter")
HOME = "-35.363261,149.165230,584,353"
# The real ArduCopter runs its own physics here at this --speedup (it keeps up to ~45x on
# this machine); tests read its own clock (time_boot_ms), so they hold at any speedup.
ARDUCOPTER_SPEEDUP = 10.0
ARDUCOPTER_DEFAULTS = {
    "FRAME_CLASS": 1, "FRAME_TYPE": 1,
    **{f"INS_ACC{k}OFFS_{a}": 0.001 for k in ("", "2") for a in "XYZ"},
    **{f"INS_ACC{k}SCAL_{a}": 1.001 for k in ("", "2") for a in "XYZ"},
}


def arducopter_binary() -> str | None:
    path = os.environ.get(ENV_BINARY)
    return path if path and os.access(path, os.X_OK) else None


def skip_without_arducopter(kind: str) -> None:
    if kind == "arducopter" and arducopter_binary() is None:
        pytest.skip(f"real ArduCopter not available: set {ENV_BINARY} to an arducopter SITL "
                    "binary (e.g. ../shared/peers/arducopter-4.6.0/arducopter)")


class Autopilot:
    kind = ""
    pymavlink_url = mavsdk_url = mavproxy_master = ""

    def stop(self) -> str:
        raise NotImplementedError

    def alive(self) -> bool:
        raise NotImplementedError


class Silbridge(Autopilot):
    kind = "silbridge"

    def __init__(self, speed: float = 6.0, extra=(), cwd=None, attempts: int = 3):
        port = free_udp_port()
        self.v = SitlVehicle([f"udpout:127.0.0.1:{port}"], speed=speed, processes=1,
                             extra=extra, cwd=cwd, attempts=attempts)
        self.port = port
        self.pymavlink_url = f"udpin:127.0.0.1:{port}"
        self.mavsdk_url = f"udpin://127.0.0.1:{port}"
        self.mavproxy_master = f"udpin:127.0.0.1:{port}"

    def stop(self) -> str:
        return self.v.stop()

    def alive(self) -> bool:
        return self.v.alive()


class ArduCopter(Autopilot):
    kind = "arducopter"

    def __init__(self, workdir: str, speedup: float = ARDUCOPTER_SPEEDUP, params: dict | None = None):
        binary = arducopter_binary()
        if binary is None:
            raise RuntimeError(f"{ENV_BINARY} is not set")
        os.makedirs(workdir, exist_ok=True)
        self.workdir = workdir
        defaults = os.path.join(workdir, "defaults.parm")
        with open(defaults, "w") as fh:
            for k, v in {**ARDUCOPTER_DEFAULTS, **(params or {})}.items():
                fh.write(f"{k} {v}\n")
        self.instance = pick_instance()
        self.tcp_port = MAVLINK_TCP_BASE + PORT_STRIDE * self.instance
        log = open(os.path.join(workdir, "sitl.log"), "w")
        self.proc = subprocess.Popen(
            [binary, "--model", "quad", "--speedup", f"{speedup:g}", "--instance",
             str(self.instance), "-w", "--defaults", defaults, "--home", HOME],
            cwd=workdir, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        log.close()
        end = time.monotonic() + 30.0
        while time.monotonic() < end:
            if self.proc.poll() is not None:
                raise AssertionError(f"arducopter exited: {self.log_tail()}")
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", self.tcp_port)) == 0:
                    break
            time.sleep(0.1)
        else:
            self.stop()
            raise AssertionError(f"arducopter never listened on {self.tcp_port}")
        self.pymavlink_url = f"tcp:127.0.0.1:{self.tcp_port}"
        self.mavsdk_url = f"tcpout://127.0.0.1:{self.tcp_port}"
        self.mavproxy_master = f"tcp:127.0.0.1:{self.tcp_port}"

    def log_tail(self) -> str:
        try:
            with open(os.path.join(self.workdir, "sitl.log"), errors="replace") as fh:
                return fh.read()[-2000:]
        except OSError:
            return ""

    def stop(self) -> str:
        stop_sitl(self.proc)
        return self.log_tail()

    def alive(self) -> bool:
        return self.proc.poll() is None


def start(kind: str, tmp_path, *, silbridge_extra=(), arducopter_params=None,
          arducopter_speedup: float = ARDUCOPTER_SPEEDUP) -> Autopilot:
    skip_without_arducopter(kind)
    if kind == "silbridge":
        return Silbridge(extra=silbridge_extra, cwd=str(tmp_path))
    return ArduCopter(str(tmp_path / "arducopter"), params=arducopter_params,
                      speedup=arducopter_speedup)


def mavproxy_path() -> str | None:
    p = shutil.which("mavproxy.py") or os.path.join(os.path.dirname(sys.executable),
                                                     "mavproxy.py")
    return p if os.path.exists(p) else None
