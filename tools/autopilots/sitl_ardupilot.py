"""ArduCopter SITL as a subprocess, and the MAVLink driver that flies it as a user would.

    binary = require_arducopter(args.arducopter)   # --arducopter, $SILBRIDGE_ARDUCOPTER, PATH
    inst = pick_instance()                          # free MAVLink TCP + JSON UDP ports
    proc = start_sitl(binary, inst, workdir, speedup=50, home=sc.home, defaults=...)
    drv = MavlinkDriver(inst, takeoff_alt_m=10, sim_time_s=..., on_takeoff=..., target=...)
    drv.start(); ...; drv.stop(); stop_sitl(proc)

SITL instance N serves MAVLink on TCP 5760 + 10 N (and waits for that
connection before it starts: the driver connects first) and sends servo
packets to UDP 9002 + 10 N. Each run gets a fresh parameter directory (the
SITL working directory, `-w` wipes its EEPROM) and a defaults file made from
our vehicle: quad X, 1000..2000 us, our physics rate, our hover throttle and
thrust curve.

The driver, in its own thread: sends a GCS heartbeat, asks for
ATTITUDE_TARGET and NAV_CONTROLLER_OUTPUT at 50 Hz and GLOBAL_POSITION_INT at
10 Hz (sim time), then every 2 s of sim time until airborne: GUIDED mode, arm,
and once armed MAV_CMD_NAV_TAKEOFF to the scenario's take-off altitude.
Arming waits for ArduCopter's own pre-arm checks (GPS, EKF), which take some
20-40 s of sim time after boot. After the take-off the scenario's setpoints
are sent by the physics thread (tools/autopilots/ardupilot_setpoints.py) through
`send_attitude_target`: every write to the link holds `_tx_lock`, so the two
threads never interleave bytes or sequence numbers.
"""

from __future__ import annotations

import math
import os
import select
import signal
import socket
import subprocess
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.autopilots.ardupilot_log import SOURCE_NAV_CONTROLLER
from silbridge.tools.autopilots.autopilot_driver import AutopilotDriver
from silbridge.tools.autopilots.autopilot_run import (
    STOP_GRACE_S,
    Autopilot,
    find_binary,
    log_tail,
    port_free,
    stop_process,
)

ENV_BINARY = "SILBRIDGE_ARDUCOPTER"
MAVLINK_TCP_BASE = 5760
JSON_UDP_BASE = 9002
PORT_STRIDE = 10
COPTER_MODE_GUIDED = 4
RETRY_SIM_S = 2.0           # between arming attempts, in sim time (what SITL's checks see)
STREAM_HZ = 50.0
POSITION_STREAM_HZ = 10.0   # GLOBAL_POSITION_INT: the altitude the setpoint forwarder reads
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
    binary = find_arducopter(explicit)
    if binary is None:
        raise SitlError(HOW_TO_GET)
    return binary


def pick_instance(start: int | None = None, tries: int = 200) -> int:
    """A SITL instance number whose MAVLink TCP ports and JSON UDP port are all free."""
    first = (os.getpid() % 97) + 1 if start is None else start
    for i in range(tries):
        n = (first + i) % 500 + 1
        tcp = [MAVLINK_TCP_BASE + PORT_STRIDE * n + k for k in (0, 2, 3)]
        if all(port_free(socket.SOCK_STREAM, p) for p in tcp) and \
                port_free(socket.SOCK_DGRAM, JSON_UDP_BASE + PORT_STRIDE * n):
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
    cmd = [binary, "--model", model, "--speedup", f"{speedup:g}",
           "--instance", str(instance), "--defaults", defaults_path, "--home", home_arg, "-w"]
    log = open(os.path.join(workdir, SITL_LOG), "w")
    try:
        return subprocess.Popen(cmd, cwd=workdir, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
    finally:
        log.close()


def stop_sitl(proc: subprocess.Popen, timeout_s: float = STOP_GRACE_S) -> None:
    """SIGTERM, then SIGKILL after timeout_s."""
    stop_process(proc, signal.SIGTERM, timeout_s)


def sitl_log_tail(workdir: str, lines: int = 8) -> str:
    return log_tail(os.path.join(workdir, SITL_LOG), lines)


ARDUCOPTER = Autopilot(
    name="ArduCopter", error=SitlError, env=ENV_BINARY, command="arducopter",
    build_hint="`./waf copter` in an ArduPilot checkout (build/sitl/bin/arducopter; "
               "docs/tutorials/arducopter-and-px4.md)",
    log_name=SITL_LOG, pick=pick_instance, stop=lambda proc, instance: stop_sitl(proc))


class MavlinkDriver(AutopilotDriver):
    """GCS over SITL's TCP port: GUIDED, arm, take off; reports ArduCopter's target and altitude."""

    def __init__(self, instance: int, *, takeoff_alt_m: float, sim_time_s, on_takeoff, target,
                 connect_timeout_s: float = 30.0, on_takeoff_sent=None, target_feed=None,
                 sim_ns=None):
        super().__init__(f"sitl-mavlink-{instance}", src_system=255, src_component=190,
                         sim_time_s=sim_time_s, target=target, on_takeoff=on_takeoff,
                         on_takeoff_sent=on_takeoff_sent, target_feed=target_feed,
                         sim_ns=sim_ns, connect_timeout_s=connect_timeout_s)
        self.addr = ("127.0.0.1", MAVLINK_TCP_BASE + PORT_STRIDE * instance)
        self.takeoff_alt_m = takeoff_alt_m
        self.mode = None
        self.takeoff_sent = False
        self.rel_alt_m: float | None = None   # GLOBAL_POSITION_INT relative_alt
        self._next_beat = 0.0                 # wall time of the next GCS heartbeat

    # pymavlink "file" interface: the codec writes here (always under _tx_lock)
    def write(self, buf: bytes) -> None:
        if self.sock is not None:
            self.sock.sendall(buf)

    def reported_alt_m(self) -> float | None:
        return self.rel_alt_m

    def _connect(self) -> None:
        end = time.monotonic() + self.connect_timeout_s
        while not self._halt.is_set():
            try:
                self.sock = socket.create_connection(self.addr, timeout=1.0)
                self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                return
            except OSError:
                if time.monotonic() > end:
                    raise SitlError(
                        f"ArduCopter SITL's MAVLink port {self.addr[1]} did not accept a "
                        f"connection in {self.connect_timeout_s:g} s") from None
                time.sleep(0.1)

    def run(self) -> None:
        try:
            self._connect()
            self._loop()
        except Exception as e:  # reported to the flight, which stops the run
            self.error = str(e) or type(e).__name__
        finally:
            if self.sock is not None:
                self.sock.close()

    def _pump(self) -> None:
        """A GCS heartbeat every wall second; what SITL sent within 20 ms, handled."""
        now = time.monotonic()
        if now >= self._next_beat:
            with self._tx_lock:
                self.codec.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._next_beat = now + 1.0
        r, _, _ = select.select([self.sock], [], [], 0.02)
        if r:
            data = self.sock.recv(65536)
            if not data:
                raise SitlError("ArduCopter SITL closed its MAVLink connection")
            for m in self.codec.parse_buffer(data) or []:
                self._handle(m)

    def _loop(self) -> None:
        next_try_sim = None
        streams_asked = False
        while not self._halt.is_set():
            self._pump()
            if self.sysid is None:
                continue
            if not streams_asked:
                for msg_id in (mav.MAVLINK_MSG_ID_ATTITUDE_TARGET,
                               mav.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT):
                    self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / STREAM_HZ)
                self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL,
                              mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 1e6 / POSITION_STREAM_HZ)
                streams_asked = True
            if self.took_off:
                continue
            t = self.sim_time_s()
            if next_try_sim is not None and t < next_try_sim:
                continue
            next_try_sim = t + RETRY_SIM_S
            if self.mode != COPTER_MODE_GUIDED:
                self._command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                              COPTER_MODE_GUIDED)
            elif not self.armed:
                self._command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            else:
                self.on_takeoff_sent()
                self._command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, 0, 0,
                              self.takeoff_alt_m)
                self.takeoff_sent = True

    def _handle(self, m) -> None:
        kind = m.get_type()
        if kind == "HEARTBEAT":
            if m.autopilot == mav.MAV_AUTOPILOT_INVALID:
                return   # another GCS
            self.sysid = m.get_srcSystem()
            self.armed = bool(m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            self.mode = m.custom_mode
        elif kind == "GLOBAL_POSITION_INT":
            self.rel_alt_m = m.relative_alt * 1e-3
        elif kind == "NAV_CONTROLLER_OUTPUT":
            self.target.set(math.radians(m.nav_roll), math.radians(m.nav_pitch),
                            math.radians(m.nav_bearing), SOURCE_NAV_CONTROLLER)
        else:
            self._report(m, kind)
