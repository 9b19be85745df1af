"""Micro-benchmark of the GCS server: frame decoding, telemetry encoding, command round trip.

    python -m silbridge.mavlink.gcs.bench [--json] [--seconds S]

* decode: frames/s through one link's FrameDecoder (the per-datagram path of the server);
* encode: telemetry messages/s built from a snapshot and packed by a link codec;
* command round trip: COMMAND_LONG -> vehicle call on another thread -> COMMAND_ACK over UDP
  loopback, p50/p99 in ms, with a vehicle thread servicing its queue at 100 Hz as fc_sil will.
  The p50 is dominated by that 10 ms service period, which is the point: it is the latency a
  GCS sees;
* server CPU: the server thread's CPU time (from /proc) while it streams what MAVSDK and QGC
  typically ask for (about 250 messages/s on one link), in % of one core.
Bounded in time; nothing spins.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import select
import socket
import statistics
import threading
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.framing import FrameDecoder, RxCounters
from silbridge.mavlink.gcs.server import GcsServer
from silbridge.mavlink.gcs.telemetry import ENCODERS, TelemetryContext
from silbridge.mavlink.gcs.vehicle_api import PidTuningRow, VehicleSnapshot


class _AcceptingVehicle:
    """Answers every request ACCEPTED: isolates the server's own latency."""

    def __getattr__(self, name):
        return lambda *args: (mav.MAV_RESULT_ACCEPTED, None)


class _Params:
    def names(self):
        return ["GCS_PID_MASK"]

    def get(self, name):
        if name != "GCS_PID_MASK":
            raise KeyError(name)
        return 15, mav.MAV_PARAM_TYPE_INT16

    def set(self, name, value):
        return "read-only in the benchmark"


def bench_decode(seconds: float) -> float:
    codec = mav.MAVLink(None, 255, 190)
    frames = [bytes(m.pack(codec)) for m in (
        mav.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3),
        mav.MAVLink_command_long_message(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0),
        mav.MAVLink_set_position_target_local_ned_message(0, 1, 1, 1, 0, 1, 2, 3, 0, 0, 0,
                                                          0, 0, 0, 0, 0))]
    dec = FrameDecoder(mav.MAVLink(None), RxCounters())
    n = 0
    end = time.perf_counter() + seconds
    t0 = time.perf_counter()
    while time.perf_counter() < end:
        for _ in range(1000):
            dec.feed(frames[n % 3], True)
            n += 1
    return n / (time.perf_counter() - t0)


def bench_encode(seconds: float) -> float:
    snap = VehicleSnapshot(home_set=True, servo_us=(1500,) * 4,
                           pid_rows=tuple(PidTuningRow(a, 1, 1, 0, 0, 0, 0) for a in (1, 2, 3, 4)))
    ctx = TelemetryContext(pid_mask=15)
    codec = mav.MAVLink(None, 1, 1)
    encoders = list(ENCODERS.values())
    n = 0
    end = time.perf_counter() + seconds
    t0 = time.perf_counter()
    while time.perf_counter() < end:
        for enc in encoders:
            for m in enc(snap, ctx):
                m.pack(codec)
                n += 1
    return n / (time.perf_counter() - t0)


@contextlib.contextmanager
def _served(server: GcsServer, tick=None):
    """The server started, a vehicle thread servicing it at 100 Hz (calling tick() too),
    and a UDP client socket: yields (server address, socket); stops everything after."""
    stop = threading.Event()

    def vehicle_loop():
        while not stop.is_set():
            server.service()
            if tick is not None:
                tick()
            stop.wait(0.01)

    vt = threading.Thread(target=vehicle_loop, daemon=True)
    vt.start()
    server.start()
    addr = next(iter(server.local_addresses().values()))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    try:
        yield addr, sock
    finally:
        stop.set()
        server.stop()
        vt.join()
        sock.close()


def bench_command_rtt(seconds: float) -> dict:
    server = GcsServer(_AcceptingVehicle(), _Params(), ["udpin:127.0.0.1:0"])
    codec = mav.MAVLink(None, 255, 190)
    parser = mav.MAVLink(None)
    rtts = []
    with _served(server) as (addr, sock):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            msg = mav.MAVLink_command_long_message(1, 1, mav.MAV_CMD_NAV_LAND, 0,
                                                   0, 0, 0, 0, 0, 0, 0)
            t0 = time.perf_counter()
            sock.sendto(msg.pack(codec), addr)
            got = False
            while not got and time.perf_counter() - t0 < 1.0:
                r, _, _ = select.select([sock], [], [], 0.5)
                if r:
                    for m in parser.parse_buffer(sock.recv(65535)) or []:
                        if m.get_type() == "COMMAND_ACK":
                            got = True
            if got:
                rtts.append((time.perf_counter() - t0) * 1e3)
    rtts.sort()
    return {"n": len(rtts), "p50_ms": statistics.median(rtts) if rtts else None,
            "p99_ms": rtts[int(0.99 * (len(rtts) - 1))] if rtts else None}


# (message id, interval us): roughly MAVSDK's telemetry requests plus QGC's data streams.
TYPICAL_STREAMS = ((mav.MAVLINK_MSG_ID_ATTITUDE_QUATERNION, 20_000),
                   (mav.MAVLINK_MSG_ID_ATTITUDE, 20_000),
                   (mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 20_000),
                   (mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 20_000),
                   (mav.MAVLINK_MSG_ID_HIGHRES_IMU, 20_000),
                   (mav.MAVLINK_MSG_ID_VFR_HUD, 100_000),
                   (mav.MAVLINK_MSG_ID_GPS_RAW_INT, 200_000),
                   (mav.MAVLINK_MSG_ID_BATTERY_STATUS, 200_000),
                   (mav.MAVLINK_MSG_ID_SERVO_OUTPUT_RAW, 100_000),
                   (mav.MAVLINK_MSG_ID_PID_TUNING, 50_000))


def _thread_cpu_s(native_id: int) -> float:
    with open(f"/proc/self/task/{native_id}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    utime, stime = int(fields[11]), int(fields[12])     # fields 14 and 15 of stat(5)
    return (utime + stime) / os.sysconf("SC_CLK_TCK")


def bench_server_cpu(seconds: float) -> dict:
    server = GcsServer(_AcceptingVehicle(), _Params(), ["udpin:127.0.0.1:0"])
    snap = VehicleSnapshot(home_set=True, servo_us=(1500,) * 4,
                           pid_rows=tuple(PidTuningRow(a, 1, 1, 0, 0, 0, 0) for a in (1, 2, 3, 4)))
    codec = mav.MAVLink(None, 255, 190)
    started = time.monotonic()

    def tick() -> None:     # streams run on the snapshots' sim time: let it advance
        server.publish(dataclasses.replace(
            snap, time_boot_ms=int((time.monotonic() - started) * 1000)))
    with _served(server, tick=tick) as (addr, sock):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        for msg_id, interval_us in TYPICAL_STREAMS:
            sock.sendto(mav.MAVLink_command_long_message(
                1, 1, mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msg_id, interval_us, 0, 0, 0, 0,
                0).pack(codec), addr)
        time.sleep(0.3)
        tid = server._thread.native_id
        cpu0, t0, n = _thread_cpu_s(tid), time.monotonic(), 0
        end = t0 + seconds
        while time.monotonic() < end:
            r, _, _ = select.select([sock], [], [], 0.1)
            if r:
                sock.recv(65535)
                n += 1
        cpu1, t1 = _thread_cpu_s(tid), time.monotonic()
    return {"msgs_per_s": n / (t1 - t0), "cpu_pct": 100.0 * (cpu1 - cpu0) / (t1 - t0)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on stdout")
    ap.add_argument("--seconds", type=float, default=1.0, help="duration of each part (s)")
    args = ap.parse_args(argv)
    res = {"decode_frames_per_s": bench_decode(args.seconds),
           "encode_msgs_per_s": bench_encode(args.seconds),
           "command_rtt": bench_command_rtt(args.seconds),
           "server_cpu": bench_server_cpu(max(args.seconds, 0.5))}
    if args.json:
        print(json.dumps(res))
    else:
        print(f"decode: {res['decode_frames_per_s']:,.0f} frames/s")
        print(f"encode: {res['encode_msgs_per_s']:,.0f} telemetry messages/s")
        r = res["command_rtt"]
        print(f"COMMAND_LONG -> ACK (vehicle services at 100 Hz): n={r['n']} "
              f"p50={r['p50_ms']:.2f} ms p99={r['p99_ms']:.2f} ms")
        c = res["server_cpu"]
        print(f"server thread streaming {c['msgs_per_s']:.0f} msg/s: {c['cpu_pct']:.1f} % "
              f"of one core")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
