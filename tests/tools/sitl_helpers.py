"""Run `silbridge fly` as a SITL vehicle for the real-client tests (MAVSDK, MAVProxy,
pymavlink): real time at --speed X, MAVLink on non-default loopback ports only, so tests that
run in parallel never collide and nothing listens on 14550/14540.
"""

from __future__ import annotations

import json
import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
import warnings

HERE = os.path.dirname(__file__)
sys.path.insert(0, os.path.join(HERE, "..", "mavlink"))

from mavtest_client import GcsClient  # noqa: E402,F401


def _ports_the_kernel_never_picks() -> range:
    """Ports below the kernel's ephemeral range (Linux: ip_local_port_range), or an empty
    range where it cannot be read or leaves no room below it."""
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            low = int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return range(0)
    return range(max(1024, low - 12000), low)


def free_udp_ports(n: int) -> list[int]:
    """n distinct free loopback UDP ports (held open together while chosen), from below the
    kernel's ephemeral range: a port is closed before another process binds it, and one the
    kernel could number for itself might meanwhile become some socket's automatic source port
    (a vehicle's udpout, a SITL's): "Address already in use" (seen in CI, MAVProxy's udpin)."""
    pool = _ports_the_kernel_never_picks()
    candidates = iter(random.sample(pool, len(pool)) if len(pool) >= 100 * n else ())
    socks = []
    try:
        while len(socks) < n:
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                s.bind(("127.0.0.1", next(candidates, 0)))   # 0: the kernel's choice
            except OSError:
                s.close()
                continue
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def free_udp_port() -> int:
    return free_udp_ports(1)[0]


class StartRetry(UserWarning):
    """A SitlVehicle start that failed a start-up check and was tried again."""


class SitlVehicle:
    """`silbridge fly --speed X` with the given MAVLink endpoints; stop() ends it.

    The constructor returns once the bridge has passed its start-up checks. A rate shortfall
    on a loaded machine no longer stops a real-time run (it is reported: "check rates SHORT",
    bridge/rate_watch.py); a start that fails another start-up check (attach, drops) is
    retried, up to `attempts` times. A vehicle that fails for any other reason fails the test
    at once.
    """

    def __init__(self, gcs_urls, *, speed: float = 8.0, duration_s: float = 600.0,
                 processes: int = 2, extra=(), json_out: bool = False, cwd=None,
                 attempts: int = 3, wait_checks: bool = True):
        self.cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--speed", str(speed),
                    "--duration", str(duration_s), "--processes", str(processes),
                    "--no-default-gcs"]
        for url in gcs_urls:
            self.cmd += ["--gcs", url]
        self.cmd += list(extra)
        if json_out:
            self.cmd.append("--json")
        self.speed = speed
        self.urls = list(gcs_urls)
        self.cwd = cwd
        self.retries = 0         # failed starts retried; each one is reported (see below)
        for attempt in range(attempts):
            self._spawn()
            if not wait_checks or self._wait_checks(90.0):
                return
            err = self.stop()
            if "start-up check" not in err or attempt == attempts - 1:
                raise AssertionError(f"the vehicle did not start (after {self.retries} "
                                     f"retries, at most {attempts - 1}):\n{err[-3000:]}")
            # A retry hides a slow or flaky start: never silently. The warning lands in
            # pytest's warnings summary with the reason, so a suite that retries shows it.
            self.retries += 1
            reason = next((ln.strip() for ln in err.splitlines() if "start-up check" in ln),
                          "start-up check failed")
            warnings.warn(StartRetry(f"SitlVehicle start retried ({self.retries} of at most "
                                     f"{attempts - 1}): {reason}"), stacklevel=2)

    def _spawn(self) -> None:
        name = f"sitl-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        self.proc = subprocess.Popen(self.cmd + ["--instance", name], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, cwd=self.cwd)
        self.out_lines: list[str] = []
        self.err_lines: list[str] = []
        self._readers = [threading.Thread(target=self._pump, args=(f, dst), daemon=True)
                         for f, dst in ((self.proc.stdout, self.out_lines),
                                        (self.proc.stderr, self.err_lines))]
        for t in self._readers:
            t.start()

    @staticmethod
    def _pump(f, dst) -> None:
        for line in f:
            dst.append(line)

    def _wait_checks(self, timeout_s: float) -> bool:
        """True once the bridge reports its last start-up check ("drops", printed last) and
        none of them failed (a rate shortfall prints SHORT, not FAILED: the run goes on)."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            lines = self.out_lines + self.err_lines
            if any(line.startswith("check drops") for line in lines):
                return not any(line.startswith("check ") and "FAILED" in line for line in lines)
            if self.proc.poll() is not None:
                return False
            time.sleep(0.05)
        return False

    def alive(self) -> bool:
        return self.proc.poll() is None

    def wait(self, timeout_s: float) -> tuple[str, str]:
        self.proc.wait(timeout=timeout_s)
        for t in self._readers:
            t.join(timeout=5.0)
        return "".join(self.out_lines), "".join(self.err_lines)

    def summary(self, timeout_s: float) -> dict:
        out, err = self.wait(timeout_s)
        for line in reversed(out.strip().splitlines()):
            if line.startswith("{"):
                return json.loads(line)
        raise AssertionError(f"no JSON summary; stderr:\n{err[-3000:]}")

    def stop(self) -> str:
        """Ctrl-C (SIGINT), as a user stops it: the flight unwinds, the MAVLink server saves
        pending parameters and the shared-memory segment is removed; SIGKILL if it hangs."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            return self.wait(15.0)[1]
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.wait(15.0)[1]


def gcs_for(port: int) -> GcsClient:
    """A pymavlink GCS (system 255, MAVProxy's id = SYSID_MYGCS) for a vehicle serving
    udpin:127.0.0.1:port; it announces itself with a heartbeat."""
    c = GcsClient(("127.0.0.1", port))
    c.send(c.mav.heartbeat_encode(6, 8, 0, 0, 0, 4))
    return c


def wait_for(client: GcsClient, mtype: str, cond=None, timeout_s: float = 30.0,
             heartbeat_every_s: float = 0.5):
    """Wait for a message while keeping our heartbeat going (GCS failsafe stays quiet)."""
    end = time.monotonic() + timeout_s
    next_hb = 0.0
    while time.monotonic() < end:
        now = time.monotonic()
        if now >= next_hb:
            client.send(client.mav.heartbeat_encode(6, 8, 0, 0, 0, 4))
            next_hb = now + heartbeat_every_s
        m = client.wait(mtype, cond, min(heartbeat_every_s, max(0.0, end - now)))
        if m is not None:
            return m
    return None
