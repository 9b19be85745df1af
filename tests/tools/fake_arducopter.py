"""A stand-in `arducopter` for the tests: the same command line, ports and protocols.

Run as `python fake_arducopter.py --model JSON:127.0.0.1 --instance N --defaults F ...`:
waits for a MAVLink connection on TCP 5760 + 10 N (as SITL does), then sends
servo packets to UDP 9002 + 10 N in lockstep with the replies. It accepts
GUIDED, arms only after 3 s of sim time (pre-arm checks), acknowledges
MAV_CMD_NAV_TAKEOFF and then holds the take-off altitude with a plain PD on
the reported position (equal PWM on all motors: no attitude control, enough
on a calm scenario). Heartbeat at 1 Hz, ATTITUDE_TARGET at 50 Hz and
GLOBAL_POSITION_INT at 10 Hz, all in sim time. Not a flight controller: it
exists to exercise the bench's process handling, MAVLink driving, setpoint
forwarding and logging end to end.

SET_ATTITUDE_TARGET is handled as ArduCopter's GCS_Mavlink.cpp and
mode_guided.cpp do with the default GUID_OPTIONS: ignored unless in GUIDED;
refused (counted) if the thrust is ignored, the body rates are part given,
or the quaternion is not unit length within 1e-3; else it becomes the angle
target (echoed on ATTITUDE_TARGET, where ArduCopter reports its shaped
target) and thrust is a climb rate (0.5 = hold; 1 = WPNAV_SPEED_UP 2.5 m/s,
0 = WPNAV_SPEED_DN 1.5 m/s down) that moves the held altitude; a target older
than GUID_TIMEOUT (3 s) falls back to level and climb 0, counted. The
attitude itself is not flown (equal PWM on all motors).
With FAKE_ARDUCOPTER_REPORT=path set, it writes on exit (also on SIGTERM)
what it received: every SET_ATTITUDE_TARGET as [sim time s, q w x y z,
thrust, type_mask, target system, target component], the refusals, the
timeouts and the messages ignored outside GUIDED.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import struct
import sys

from pymavlink.dialects.v20 import ardupilotmega as mav

_PKT = struct.Struct("<HHI16H")


class Tcp:
    def __init__(self, conn):
        self.conn = conn

    def write(self, buf):
        self.conn.sendall(buf)


GUID_TIMEOUT_S = 3.0
SPEED_UP_M_S, SPEED_DN_M_S = 2.5, 1.5
RATES_IGNORE, THRUST_IGNORE = 0b111, 1 << 6


def climb_rate_m_s(thrust: float) -> float:
    """ArduCopter's reading of SET_ATTITUDE_TARGET.thrust with GUID_OPTIONS bit 3 clear."""
    thrust = min(max(thrust, 0.0), 1.0)
    if thrust == 0.5:
        return 0.0
    if thrust > 0.5:
        return (thrust - 0.5) * 2.0 * SPEED_UP_M_S
    return (0.5 - thrust) * 2.0 * -SPEED_DN_M_S


class Received:
    """What the fake was sent, for FAKE_ARDUCOPTER_REPORT."""

    def __init__(self):
        self.targets, self.refused, self.timeouts, self.not_guided = [], [], 0, 0

    def write(self) -> None:
        path = os.environ.get("FAKE_ARDUCOPTER_REPORT")
        if path:
            # Whole or not at all: written aside, then renamed into place.
            with open(path + ".part", "w") as fh:
                json.dump({"set_attitude_target": self.targets, "refused": self.refused,
                           "timeouts": self.timeouts, "not_guided": self.not_guided}, fh)
            os.replace(path + ".part", path)


def main() -> int:
    rx = Received()
    # stop_sitl() terminates us: unwind through `finally` so the report is written.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        return fly(rx)
    finally:
        # The bench closes our MAVLink link (we exit) and terminates us at about the same
        # time: a SIGTERM must not cut the report short.
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        rx.write()


def fly(rx: Received) -> int:
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
    codec.robust_parsing = True
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.settimeout(5.0)
    phys = ("127.0.0.1", 9002 + 10 * a.instance)
    mode, armed, alt_cmd = 0, False, None
    q_target, climb, target_t = [1.0, 0.0, 0.0, 0.0], 0.0, None
    state = {"timestamp": 0.0, "position": [0, 0, 0], "velocity": [0, 0, 0]}
    frame, next_beat, next_att, next_pos = 0, 0.0, 0.0, 0.0
    while True:
        t = state["timestamp"]
        if alt_cmd is None:
            pwm = 1000
        else:   # PD on height above home (NED down is negative up)
            up, vup = -state["position"][2], -state["velocity"][2]
            pwm = int(min(max(hover_us + 60.0 * (alt_cmd - up) - 80.0 * vup, 1000), 2000))
        udp.sendto(_PKT.pack(18458, 1000, frame, *([pwm] * 4 + [0] * 12)), phys)
        try:
            new = json.loads(udp.recv(65536))
        except (socket.timeout, ConnectionRefusedError):
            return 3
        dt = new["timestamp"] - t
        state = new
        frame += 1
        if target_t is not None:
            if t - target_t > GUID_TIMEOUT_S:   # ArduCopter: back to level, climb 0
                rx.timeouts += 1
                q_target, climb, target_t = [1.0, 0.0, 0.0, 0.0], 0.0, None
            elif alt_cmd is not None:
                alt_cmd += climb * dt
        if t >= next_beat:
            base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
                mav.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
            codec.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA, base,
                                 mode, mav.MAV_STATE_ACTIVE)
            next_beat = t + 1.0
        if t >= next_att:
            codec.attitude_target_send(int(t * 1000), 0, q_target, 0, 0, 0, 0.5)
            next_att = t + 0.02
        if t >= next_pos:
            up_mm = int(round(-state["position"][2] * 1000.0))
            codec.global_position_int_send(int(t * 1000), 0, 0, up_mm, up_mm, 0, 0, 0, 0)
            next_pos = t + 0.1
        try:
            data = conn.recv(65536)
        except BlockingIOError:
            continue
        if not data:
            return 0
        for m in codec.parse_buffer(data) or []:
            kind = m.get_type()
            if kind == "SET_ATTITUDE_TARGET":
                if mode != 4:
                    rx.not_guided += 1
                    continue
                q = list(m.q)
                rx.targets.append([t, *q, m.thrust, m.type_mask, m.target_system,
                                   m.target_component])
                rates = m.type_mask & RATES_IGNORE
                if m.type_mask & THRUST_IGNORE or rates not in (0, RATES_IGNORE) or \
                        abs(sum(v * v for v in q) - 1.0) > 1e-3:
                    rx.refused.append([t, m.type_mask])
                    continue
                q_target, climb, target_t = q, climb_rate_m_s(m.thrust), t
                continue
            if kind != "COMMAND_LONG":
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
