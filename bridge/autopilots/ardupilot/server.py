"""The UDP side of the ArduPilot JSON physics: bind SITL's port, answer every packet.

    server = JsonPhysicsServer(physics, ("127.0.0.1", 9002))
    result = server.serve(duration_s=120.0)

SITL is the clock master in lockstep: it sends a servo packet, blocks until
our reply, and only then runs its next frame, so `serve` simply answers
packets until the sim time reaches duration_s (or the vehicle crashes, or
`stop()` says so). The first packet may take long (the user starts SITL
after us; SITL boots), later silence means SITL died or hung: both have
their own timeout and raise a user-facing error saying what to check.
"""

from __future__ import annotations

import select
import socket
import time
from dataclasses import dataclass, field

from silbridge.bridge.autopilots.ardupilot.json_protocol import ArduPilotProtocolError
from silbridge.bridge.errors import BridgeError
from silbridge.bridge.link_spin import spin_poll
from silbridge.bridge.serve_loop import ServeResult, ended_by, stop_asked
from silbridge.shm.records import NS_PER_S as _NS


class SitlLost(BridgeError):
    """SITL never connected, or stopped sending servo packets."""


@dataclass
class JsonRunResult(ServeResult):
    notes: list = field(default_factory=list)


def parse_address(text: str | None, default_port: int) -> tuple[str, int]:
    """'HOST:PORT', 'HOST', ':PORT' or None -> (host, port)."""
    if not text:
        return "127.0.0.1", default_port
    host, sep, port = text.rpartition(":")
    if not sep:
        return text, default_port
    try:
        return host or "127.0.0.1", int(port)
    except ValueError:
        raise ArduPilotProtocolError(f"--link-addr wants HOST:PORT, got {text!r}") from None


class JsonPhysicsServer:
    def __init__(self, physics, address=("127.0.0.1", 9002)):
        self.physics = physics
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind(address)
        except OSError as e:
            self.sock.close()
            raise BridgeError(f"cannot listen for ArduPilot SITL on {address[0]}:{address[1]} "
                              f"({e.strerror}): another bridge or physics program uses it; "
                              "stop it or pick another --link-addr / SITL --instance") from None
        self.address = self.sock.getsockname()

    def close(self) -> None:
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def serve(self, duration_s: float, *, connect_timeout_s: float = 120.0,
              idle_timeout_s: float = 10.0, stop=None, poll_s: float = 0.2,
              spin_us: float = 0.0) -> JsonRunResult:
        """Answer servo packets until duration_s of sim time; see the module text.

        spin_us: after each reply, poll the socket without sleeping for up to this long
        before sleeping in select() (bridge/link_spin.py says when that pays; 0, the
        default, sleeps at once).
        """
        phys = self.physics
        sock = self.sock
        sock.setblocking(False)     # recvfrom never sleeps; select() does the waiting
        spin_ns = int(spin_us * 1000)
        recv = sock.recvfrom

        def poll():
            try:
                return recv(512)
            except BlockingIOError:
                return None

        mono_ns = time.monotonic_ns
        end_ns = int(round(duration_s * _NS))
        t0 = time.monotonic()
        last_rx = None
        stopped_by = "duration"
        while phys.sim.sim_ns < end_ns:
            got = spin_poll(poll, spin_ns if last_rx is not None else 0)
            data = None
            if got is not None:
                data, src = got
            if data is None:
                if select.select([sock], [], [], poll_s)[0]:
                    continue
                now = time.monotonic()
                if stop_asked(stop):
                    stopped_by = "stop"
                    break
                if last_rx is None and now - t0 > connect_timeout_s:
                    raise SitlLost(
                        f"no servo packet from ArduPilot SITL on {self.address[0]}:"
                        f"{self.address[1]} in {connect_timeout_s:g} s: start `arducopter "
                        "--model JSON` (its instance N sends to port 9002 + 10 N)") from None
                if last_rx is not None and now - last_rx > idle_timeout_s:
                    raise SitlLost(
                        f"ArduPilot SITL stopped sending servo packets for "
                        f"{idle_timeout_s:g} s at sim time {phys.sim.sim_ns / _NS:.3f} s: "
                        "did it crash or was it stopped? Check its console output") from None
                continue
            rx_ns = mono_ns()
            last_rx = rx_ns * 1e-9
            sock.sendto(phys.handle(data, src, rx_ns), src)
            phys.sent(mono_ns())
            end = ended_by(phys.sim, stop)
            if end:
                stopped_by = end
                break
        return JsonRunResult.of(phys.sim, t0, phys.stats(), stopped_by)
