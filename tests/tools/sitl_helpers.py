"""Run `silbridge fly` as a SITL vehicle for the real-client tests (MAVSDK, MAVProxy,
pymavlink): real time at --speed X, MAVLink on non-default loopback ports only, so tests that
run in parallel never collide and nothing listens on 14550/14540.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
import uuid

HERE = os.path.dirname(__file__)
sys.path.insert(0, os.path.join(HERE, "..", "mavlink"))

from mavtest_client import GcsClient  # noqa: E402,F401


def free_udp_ports(n: int) -> list[int]:
    """n distinct free loopback UDP ports (held open together while chosen)."""
    socks = []
    try:
        for _ in range(n):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.bind(("127.0.0.1", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def free_udp_port() -> int:
    return free_udp_ports(1)[0]


class SitlVehicle:
    """`silbridge fly --speed X` with the given MAVLink endpoints; stop() ends it."""

    def __init__(self, gcs_urls, *, speed: float = 8.0, duration_s: float = 600.0,
                 processes: int = 2, extra=(), json_out: bool = False, cwd=None):
        cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--speed", str(speed),
               "--duration", str(duration_s), "--processes", str(processes), "--no-default-gcs",
               "--instance", f"sitl-{os.getpid()}-{uuid.uuid4().hex[:8]}"]
        for url in gcs_urls:
            cmd += ["--gcs", url]
        cmd += list(extra)
        if json_out:
            cmd.append("--json")
        self.speed = speed
        self.urls = list(gcs_urls)
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, cwd=cwd)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def wait(self, timeout_s: float) -> tuple[str, str]:
        return self.proc.communicate(timeout=timeout_s)

    def summary(self, timeout_s: float) -> dict:
        out, err = self.wait(timeout_s)
        for line in reversed(out.strip().splitlines()):
            if line.startswith("{"):
                return json.loads(line)
        raise AssertionError(f"no JSON summary; stderr:\n{err[-3000:]}")

    def stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err or ""


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
