"""A stand-in `arducopter` for the tests: the same command line, ports and protocols.

Run as `python fake_arducopter.py --model JSON:127.0.0.1 --instance N --defaults F ...`:
waits for a MAVLink connection on TCP 5760 + 10 N (as SITL does), then sends
servo packets to UDP 9002 + 10 N in lockstep with the replies. It accepts
GUIDED, arms only after 3 s of sim time (pre-arm checks), acknowledges
MAV_CMD_NAV_TAKEOFF and then holds the take-off altitude with a plain PD on
the reported position (equal PWM on all motors: no attitude control, enough
on a calm scenario). Heartbeat at 1 Hz and ATTITUDE_TARGET (level) at 50 Hz,
both in sim time. Not a flight controller: it exists to exercise the bench's
process handling, MAVLink driving and logging end to end.
"""

from __future__ import annotations

import argparse
import json
import socket
import struct

from pymavlink.dialects.v20 import ardupilotmega as mav

_PKT = struct.Struct("<HHI16H")


class Tcp:
    def __init__(self, conn):
        self.conn = conn

    def write(self, buf):
        self.conn.sendall(buf)


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--model")
    p.add_argument("--speedup")
    p.add_argument("--instance", type=int, default=0)
    p.add_argument("--defaults")
    p.add_argument("--home")
    p.add_argument("-w", action="store_true")
    a = p.parse_args()
    params = dict(line.split() for line in open(a.defaults) if line.strip())
    hover_us = 1000.0 + 1000.0 * float(params["MOT_THST_HOVER"])
    lst = socket.socket()
    lst.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    lst.bind(("127.0.0.1", 5760 + 10 * a.instance))
    lst.listen(1)
    conn, _ = lst.accept()
    conn.setblocking(False)
    codec = mav.MAVLink(Tcp(conn), srcSystem=1, srcComponent=1)
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.settimeout(5.0)
    phys = ("127.0.0.1", 9002 + 10 * a.instance)
    mode, armed, alt_cmd = 0, False, None
    state = {"timestamp": 0.0, "position": [0, 0, 0], "velocity": [0, 0, 0]}
    frame, next_beat, next_att = 0, 0.0, 0.0
    while True:
        t = state["timestamp"]
        if alt_cmd is None:
            pwm = 1000
        else:   # PD on height above home (NED down is negative up)
            up, vup = -state["position"][2], -state["velocity"][2]
            pwm = int(min(max(hover_us + 60.0 * (alt_cmd - up) - 80.0 * vup, 1000), 2000))
        udp.sendto(_PKT.pack(18458, 1000, frame, *([pwm] * 4 + [0] * 12)), phys)
        try:
            state = json.loads(udp.recv(65536))
        except (socket.timeout, ConnectionRefusedError):
            return 3
        frame += 1
        if t >= next_beat:
            base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
                mav.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
            codec.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA, base,
                                 mode, mav.MAV_STATE_ACTIVE)
            next_beat = t + 1.0
        if t >= next_att:
            codec.attitude_target_send(int(t * 1000), 0, [1, 0, 0, 0], 0, 0, 0, 0.5)
            next_att = t + 0.02
        try:
            data = conn.recv(65536)
        except BlockingIOError:
            continue
        if not data:
            return 0
        for m in codec.parse_buffer(data) or []:
            if m.get_type() != "COMMAND_LONG":
                continue
            result = mav.MAV_RESULT_ACCEPTED
            if m.command == mav.MAV_CMD_DO_SET_MODE:
                mode = int(m.param2)
            elif m.command == mav.MAV_CMD_COMPONENT_ARM_DISARM:
                if t < 3.0:
                    result = mav.MAV_RESULT_FAILED
                    codec.statustext_send(mav.MAV_SEVERITY_CRITICAL, b"PreArm: EKF not ready")
                else:
                    armed = True
            elif m.command == mav.MAV_CMD_NAV_TAKEOFF:
                if armed and mode == 4:
                    alt_cmd = m.param7
                else:
                    result = mav.MAV_RESULT_FAILED
            codec.command_ack_send(m.command, result)


if __name__ == "__main__":
    raise SystemExit(main())
