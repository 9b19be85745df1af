"""HIL over a serial line (`--link-addr serial:DEV:BAUD`), end to end between the bridge and our
FC as two programs, over two real pseudo-terminals joined the way a null-modem cable (or
`socat PTY PTY`) joins two ports. Same seed -> same trace hash as over shared memory: the
same messages, framed on the line, carry the same flight bit for bit."""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import threading

import pytest

from silbridge.mavlink.hil.hil_errors import HilConnectError
from silbridge.mavlink.hil.hil_serial import parse_serial
from silbridge.tools.loop.flight import FlightOptions, fly_two_processes

CLI = [sys.executable, "-m", "silbridge.tools"]
_FLIGHT = ["--scenario", "S4", "--duration", "1.5", "--seed", "11", "--lockstep"]


class NullModem(threading.Thread):
    """Two pseudo-terminals; bytes written to one come out of the other."""

    def __init__(self):
        super().__init__(daemon=True)
        self.m1, self.s1 = os.openpty()
        self.m2, self.s2 = os.openpty()
        self.names = (os.ttyname(self.s1), os.ttyname(self.s2))
        self.halt = threading.Event()
        self.bytes = 0

    def run(self) -> None:
        peer = {self.m1: self.m2, self.m2: self.m1}
        while not self.halt.is_set():
            r, _, _ = select.select([self.m1, self.m2], [], [], 0.05)
            for fd in r:
                try:
                    data = os.read(fd, 65536)
                except OSError:
                    continue
                view = memoryview(data)
                while view:
                    n = os.write(peer[fd], view)
                    view = view[n:]
                self.bytes += len(data)

    def close(self) -> None:
        self.halt.set()
        self.join(2)
        for fd in (self.m1, self.s1, self.m2, self.s2):
            os.close(fd)


def test_parse_serial_address():
    assert parse_serial("serial:/dev/ttyACM0:921600") == ("/dev/ttyACM0", 921600)
    assert parse_serial("serial:/dev/ttyUSB1") == ("/dev/ttyUSB1", 921600)
    with pytest.raises(HilConnectError, match="serial:/dev/PORT"):
        parse_serial("serial:ttyACM0")


def test_bridge_and_fc_fly_over_a_serial_line_as_over_shared_memory(tmp_path):
    ref = fly_two_processes(FlightOptions(scenario="S4", duration_s=1.5, seed=11, lockstep=True,
                                          instance="serialref"), out=lambda line: None)
    line = NullModem()
    line.start()
    bridge = fc = None
    try:
        bridge = subprocess.Popen(CLI + ["bridge", *_FLIGHT, "--transport", "tcp", "--json",
                                         "--link-addr", f"serial:{line.names[0]}:921600"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        fc = subprocess.Popen(CLI + ["fc", "--transport", "tcp",
                                     "--link-addr", f"serial:{line.names[1]}:921600"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        out, err = bridge.communicate(timeout=80)
        fc.wait(timeout=20)
    finally:
        for p in (bridge, fc):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
        line.close()
    assert bridge.returncode == 0, err[-2000:]
    assert fc.returncode == 0, fc.stderr.read()[-2000:]
    s = json.loads(out)
    assert s["trace_hash"] == ref["trace_hash"]
    assert not s["crashed"] and s["overwritten"] == 0
    assert line.bytes > 100_000              # it really went over the line
