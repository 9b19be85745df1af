"""ArduCopter SITL as a subprocess: find it, pick a free instance, start it on our vehicle, stop it.

    binary = require_arducopter(args.arducopter)   # --arducopter, $SILBRIDGE_ARDUCOPTER, PATH
    inst = pick_instance()                          # free MAVLink TCP + JSON UDP ports
    proc = start_sitl(binary, inst, workdir, speedup=50, home=sc.home, defaults_path=...)
    ...; stop_sitl(proc)                            # SIGTERM, then SIGKILL

SITL instance N serves MAVLink on TCP 5760 + 10 N (and waits for that connection before it
starts: the driver, tools/autopilots/ardupilot/driver.py, connects first) and sends servo
packets to UDP 9002 + 10 N (bridge/autopilots/ardupilot/server.py answers them). Each run
gets a fresh parameter directory (the SITL working directory, `-w` wipes its EEPROM) and a
defaults file made from our vehicle: quad X, 1000..2000 us, our physics rate, our hover
throttle and thrust curve.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess

from silbridge.bridge.autopilots.ardupilot.json_protocol import PORT_STRIDE, sitl_port

from silbridge.tools.autopilots.common.process import (STOP_GRACE_S, Autopilot, find_binary,
                                                       port_free, require_binary, spawn,
                                                       stop_process)

ENV_BINARY = "SILBRIDGE_ARDUCOPTER"
MAVLINK_TCP_BASE = 5760     # + PORT_STRIDE N for instance N, as its JSON port (sitl_port)
SITL_LOG = "sitl.log"       # SITL's console output, in its working directory

HOW_TO_GET = (
    "no ArduCopter SITL binary: give --arducopter PATH, set SILBRIDGE_ARDUCOPTER, or put "
    "`arducopter` on PATH. Build it (ArduCopter 4.6.0): git clone --recurse-submodules -b "
    "Copter-4.6.0 https://github.com/ArduPilot/ardupilot && cd ardupilot && "
    "Tools/environment_install/install-prereqs-ubuntu.sh -y && ./waf configure --board sitl "
    "&& ./waf copter  (binary: build/sitl/bin/arducopter); see "
    "docs/tutorials/arducopter-and-px4.md")


class SitlError(Exception):
    user_facing = True


def find_arducopter(explicit: str | None = None) -> str | None:
    """The arducopter binary to use, or None: --arducopter, then $SILBRIDGE_ARDUCOPTER, then
    PATH. A given path that is not an executable file is a SitlError."""
    return find_binary(ARDUCOPTER, explicit)


def require_arducopter(explicit: str | None = None) -> str:
    """find_arducopter, or SitlError saying how to build one: for the commands that fly it."""
    return require_binary(ARDUCOPTER, explicit)


def pick_instance(start: int | None = None, tries: int = 200) -> int:
    """A SITL instance number whose MAVLink TCP ports and JSON UDP port are all free."""
    first = (os.getpid() % 97) + 1 if start is None else start
    for i in range(tries):
        n = (first + i) % 500 + 1
        tcp = [MAVLINK_TCP_BASE + PORT_STRIDE * n + k for k in (0, 2, 3)]
        if all(port_free(socket.SOCK_STREAM, p) for p in tcp) and \
                port_free(socket.SOCK_DGRAM, sitl_port(n)):
            return n
    raise SitlError("no free SITL instance (ports 5760+10N, 9002+10N) in 200 tries: stop "
                    "stale arducopter processes")


def sitl_defaults(sim, physics_hz: float, overrides: dict | None = None) -> dict:
    """ArduCopter parameters matching our vehicle (written as the --defaults file)."""
    expo = sim.fdm.model_constant("quadx/thrust-expo")
    params = {
        "FRAME_CLASS": 1,          # quad
        "FRAME_TYPE": 1,           # X: SERVO1..4 = motors 1..4 = our order
        "SIM_RATE_HZ": int(round(physics_hz)),   # one packet per 1 ms physics step
        "SCHED_LOOP_RATE": 400,    # the 400 Hz PWM of our FC
        "MOT_PWM_MIN": 1000,
        "MOT_PWM_MAX": 2000,
        "MOT_THST_EXPO": round(expo, 4),
        "MOT_THST_HOVER": round(min(max(sim.hover_throttle, 0.125), 0.6875), 4),
        # S4 commands tilts up to 35 deg; the default 3000 cdeg (30 deg) would scale them
        # down (GUIDED angle control limits the lean to ANGLE_MAX in mode_guided.cpp).
        "ANGLE_MAX": 4500,
    }
    params.update(overrides or {})
    return params


def write_defaults(path: str, params: dict) -> None:
    with open(path, "w") as fh:
        for name, value in params.items():
            fh.write(f"{name} {value:g}\n" if isinstance(value, float) else f"{name} {value}\n")


def start_sitl(binary: str, instance: int, workdir: str, *, speedup: float, home,
               defaults_path: str, model: str = "JSON:127.0.0.1") -> subprocess.Popen:
    """arducopter --model JSON in workdir (fresh EEPROM); console output to workdir/sitl.log.
    model: another --model (e.g. "quad", SITL's own physics: the speed reference)."""
    home_arg = f"{home.lat_deg},{home.lon_deg},{home.alt_m},{home.heading_deg}"
    return spawn([binary, "--model", model, "--speedup", f"{speedup:g}",
                  "--instance", str(instance), "--defaults", defaults_path, "--home", home_arg,
                  "-w"], workdir, SITL_LOG)


def stop_sitl(proc: subprocess.Popen, timeout_s: float = STOP_GRACE_S) -> None:
    """SIGTERM, then SIGKILL after timeout_s."""
    stop_process(proc, signal.SIGTERM, timeout_s)


ARDUCOPTER = Autopilot(
    name="ArduCopter", error=SitlError, env=ENV_BINARY, command="arducopter",
    how_to_get=HOW_TO_GET, log_name=SITL_LOG, pick=pick_instance,
    build_hint="`./waf copter` in an ArduPilot checkout (build/sitl/bin/arducopter; "
               "docs/tutorials/arducopter-and-px4.md)",
    stop=lambda proc, instance: stop_sitl(proc))
