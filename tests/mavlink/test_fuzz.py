"""Malformed input: >= 100,000 bad frames at the real server over UDP (and a TCP stream),
each counted in the right bucket, none crashing or stalling it, the server answering after.

Frames are sent in small batches and the test waits until the server has read each batch,
so no datagram is lost in the kernel and the counters can be checked exactly.
"""

from __future__ import annotations

import random
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from mavtest_client import wait_until

BATCH = 100


def _codec(sysid=200, compid=1):
    return mav.MAVLink(None, srcSystem=sysid, srcComponent=compid)


def _base_frames() -> list[bytes]:
    c = _codec()
    msgs = [mav.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3),
            mav.MAVLink_system_time_message(1_700_000_000_000_000, 1234),
            mav.MAVLink_timesync_message(5, 6),
            mav.MAVLink_param_request_read_message(9, 9, b"NOT_FOR_US", -1),
            mav.MAVLink_command_long_message(9, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0),
            mav.MAVLink_statustext_message(6, b"hello from a fuzzer, a long-ish text")]
    out = []
    for m in msgs:
        out.append(bytes(m.pack(c)))
        c.seq = (c.seq + 1) % 256
    return out


def _v1_frame(rng) -> bytes:
    # MAVLink 1 HEARTBEAT with a wrong CRC
    payload = bytes(9)
    return bytes([0xFE, 9, rng.randrange(256), 200, 1, 0]) + payload + b"\x00\x00"


def _unknown_frame(rng) -> bytes:
    while True:
        msgid = rng.randrange(1 << 24)
        if msgid not in mav.mavlink_map:
            break
    n = rng.randrange(0, 40)
    header = bytes([0xFD, n, 0, 0, rng.randrange(256), 200, 1, msgid & 0xFF, (msgid >> 8) & 0xFF,
                    msgid >> 16])
    return header + rng.randbytes(n) + rng.randbytes(2)


def _garbage(rng) -> bytes:
    data = bytearray(rng.randbytes(rng.randrange(1, 120)))
    for i, b in enumerate(data):
        if b in (0xFD, 0xFE):
            data[i] = 0x55
    return bytes(data)


class Sender:
    def __init__(self, addr):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.addr = addr
        self.sent = 0

    def send(self, data: bytes, server) -> None:
        self.sock.sendto(data, self.addr)
        self.sent += 1
        if self.sent % BATCH == 0:
            self.sync(server)

    def sync(self, server) -> None:
        target = self.base + self.sent
        assert wait_until(lambda: server.counters()["rx_packets"] >= target, 10.0, 0.001), \
            "server stopped reading"


def test_fuzz_100k_malformed_udp_frames(env):
    server = env.server
    rng = random.Random(20261122)
    base = _base_frames()
    assert wait_until(lambda: server.counters()["rx_ok"] >= 1)    # the fixture's heartbeat
    before = server.counters()
    s = Sender(next(iter(server.local_addresses().values())))
    s.base = before["rx_packets"]
    exp = dict(ok=0, bad_crc=0, malformed=0, unknown=0)
    n_exact = 80_000
    for i in range(n_exact):
        kind = i % 8
        f = bytearray(rng.choice(base))
        if kind == 0:                                   # wrong CRC
            f[-1] ^= rng.randrange(1, 256)
            exp["bad_crc"] += 1
        elif kind == 1:                                 # truncated
            f = f[:rng.randrange(1, len(f))]
            exp["malformed"] += 1
        elif kind == 2:                                 # unknown message id
            f = bytearray(_unknown_frame(rng))
            exp["unknown"] += 1
        elif kind == 3:                                 # noise
            f = bytearray(_garbage(rng))
            exp["malformed"] += 1
        elif kind == 4:                                 # incompatibility flag we cannot honour
            f[2] |= 0x02
            exp["malformed"] += 1
        elif kind == 5:                                 # noise, then a good frame: resync
            f = bytearray(_garbage(rng)) + f
            exp["malformed"] += 1
            exp["ok"] += 1
        elif kind == 6:                                 # MAVLink 1 frame, bad CRC
            f = bytearray(_v1_frame(rng))
            exp["bad_crc"] += 1
        else:                                           # empty datagram
            f = bytearray()
        s.send(bytes(f), server)
    s.sync(server)
    mid = server.counters()
    assert mid["rx_ok"] - before["rx_ok"] == exp["ok"]
    assert mid["rx_bad_crc"] - before["rx_bad_crc"] == exp["bad_crc"]
    assert mid["rx_malformed"] - before["rx_malformed"] == exp["malformed"]
    assert mid["rx_unknown"] - before["rx_unknown"] == exp["unknown"]

    # random bit flips and byte splices: every datagram must be accounted for somewhere
    n_random = 20_000
    for _ in range(n_random):
        f = bytearray(rng.choice(base))
        for _ in range(rng.randrange(1, 4)):
            pos = rng.randrange(len(f))
            f[pos] ^= 1 << rng.randrange(8)
        if rng.random() < 0.3:
            f = f[:rng.randrange(1, len(f))] + rng.choice(base)[rng.randrange(5):]
        s.send(bytes(f), server)
    s.sync(server)
    after = server.counters()
    seen = sum(after[k] - mid[k] for k in ("rx_ok", "rx_bad_crc", "rx_malformed", "rx_unknown"))
    assert seen >= n_random
    assert after.get("handler_errors", 0) == 0
    # Count what actually went out and came in, not the loop bounds: every datagram sent was
    # read by the server (nothing else talks to it meanwhile), and there were 100,000.
    assert s.sent >= 100_000
    assert after["rx_packets"] - before["rx_packets"] == s.sent

    # still answering, and the vehicle loop kept running
    env.client.send(mav.MAVLink_param_request_read_message(1, 1, b"RTL_ALT", -1))
    assert env.client.wait("PARAM_VALUE", lambda m: m.param_id == "RTL_ALT") is not None
    ack = env.client.command_long(mav.MAV_CMD_DO_SET_MODE, p1=1, p2=5)
    assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED
    t_boot = server.snapshots.latest.time_boot_ms
    assert wait_until(lambda: server.snapshots.latest.time_boot_ms > t_boot, 1.0)


def test_fuzz_tcp_stream(make_env):
    e = make_env(endpoints=["tcpin:127.0.0.1:0"])
    addr = next(iter(e.server.local_addresses().values()))
    rng = random.Random(7)
    base = _base_frames()
    sock = socket.create_connection(addr)
    try:
        codec = mav.MAVLink(None, srcSystem=255, srcComponent=190)
        stream = bytearray()
        for _ in range(5000):
            f = bytearray(rng.choice(base))
            f[rng.randrange(len(f))] ^= 1 << rng.randrange(8)
            stream += f + _garbage(rng)
        # a final good request, after enough noise to flush any half frame
        stream += bytes(300)
        stream += mav.MAVLink_param_request_read_message(1, 1, b"ANGLE_MAX", -1).pack(codec)
        for i in range(0, len(stream), 997):           # odd chunk sizes split frames
            sock.sendall(stream[i:i + 997])
        sock.settimeout(5.0)
        parser = mav.MAVLink(None)
        parser.robust_parsing = True
        found = False
        end = time.monotonic() + 5.0
        while not found and time.monotonic() < end:
            for m in parser.parse_buffer(sock.recv(65536)) or []:
                if m.get_type() == "PARAM_VALUE" and m.param_id == "ANGLE_MAX":
                    found = True
        assert found
        c = e.server.counters()
        assert c["rx_bad_crc"] + c["rx_malformed"] + c["rx_unknown"] >= 5000
        assert c.get("handler_errors", 0) == 0
    finally:
        sock.close()
