"""The ArduPilot SITL JSON physics against a small fake SITL written here.

The fake sends servo packets over real UDP to a real JsonPhysicsServer (real
JSBSim behind it) and reads the replies the way SITL's parser does (strstr for
the key, the value right after `"key":`), so a reply SITL could not read fails
here. Covered: fields, units and frames at rest and in a climb, framing,
lockstep (one step per new frame, none for a resend; with the server sleeping or
spinning between packets), drops, reset when SITL
restarts (timestamp goes back), 32-channel packets, and refusal of a wrong
magic with a message that says what to check.
"""

from __future__ import annotations

import json
import math
import re
import socket
import threading

import pytest

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.frames import euler_from_quat
from silbridge.bridge.autopilots.ardupilot.server import JsonPhysicsServer, SitlLost, parse_address
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator

_FLOAT = r"([-+0-9.eE]+|nan|inf)"


def sitl_read(line: str) -> dict:
    """Read a reply as libraries/SITL/SIM_JSON.cpp does: strstr, skip `key":`, scan."""
    out = {}
    for section, key, n in (("", "timestamp", 1), ("imu", "gyro", 3), ("imu", "accel_body", 3),
                            ("", "position", 3), ("", "quaternion", 4), ("", "attitude", 3),
                            ("", "velocity", 3)):
        p = line.find(section) + len(section) + 1 if section else 0
        i = line.find(key, p)
        assert i >= 0, f"{key} missing in {line}"
        rest = line[i + len(key) + 2:]
        if n == 1:
            out[key] = float(re.match(_FLOAT, rest).group(1))
        else:
            pat = r"\[" + r",\s*".join([_FLOAT] * n) + r"\]"
            m = re.match(pat, rest)
            assert m, f"{key}: SITL's scanf would not read {rest[:60]!r}"
            out[key] = [float(v) for v in m.groups()]
    return out


class FakeSitl:
    """ArduPilot SITL's side of the JSON link: one servo packet, wait for one reply."""

    def __init__(self, server_addr):
        self.addr = server_addr
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(10.0)
        self.frame = 0

    def exchange(self, pwm=(1000,) * 4, frame=None, channels=16, rate_hz=1000) -> tuple:
        if frame is None:
            self.frame += 1
            frame = self.frame
        self.sock.sendto(apj.encode_servo_packet(frame, pwm, rate_hz, channels), self.addr)
        raw = self.sock.recv(65536)
        return raw, sitl_read(raw.decode())

    def send_raw(self, data: bytes) -> None:
        self.sock.sendto(data, self.addr)

    def close(self):
        self.sock.close()


@pytest.fixture(params=[0.0, 500.0], ids=["sleeping", "spinning"])
def link(request):
    """A served ArduPilotPhysics on an ephemeral port and a FakeSitl talking to it; the
    server sleeps in select() between packets, or spins first (bridge/link_spin.py)."""
    sc = load_scenario("S1")
    notes = []
    phys = ArduPilotPhysics(lambda: Simulator(sc), note=notes.append)
    server = JsonPhysicsServer(phys, ("127.0.0.1", 0))
    done = threading.Event()
    box = {}

    def serve():
        try:
            box["result"] = server.serve(1e6, stop=done.is_set, poll_s=0.02,
                                         spin_us=request.param)
        except Exception as e:   # handed to the test thread
            box["error"] = e

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    sitl = FakeSitl(server.address)
    yield sitl, phys, box, notes
    done.set()
    t.join(5.0)
    sitl.close()
    server.close()


def test_reply_framing_and_fields_at_rest(link):
    sitl, phys, _, _ = link
    raw, _ = sitl.exchange()
    # One JSON object with a newline before and after, no space after any colon.
    assert raw.startswith(b"\n") and raw.endswith(b"\n") and raw.count(b"\n") == 2
    assert b": " not in raw
    obj = json.loads(raw)
    assert set(obj) == {"timestamp", "imu", "position", "attitude", "quaternion", "velocity"}
    assert set(obj["imu"]) == {"gyro", "accel_body"}
    for _ in range(199):
        raw, st = sitl.exchange()
    assert st["timestamp"] == pytest.approx(0.2, abs=1e-12)
    # On the ground, motors stopped: specific force z = -g (up is -z in FRD), no rotation.
    ax, ay, az = st["accel_body"]
    assert az == pytest.approx(-9.81, abs=0.4)
    assert abs(ax) < 0.4 and abs(ay) < 0.4
    assert max(abs(v) for v in st["gyro"]) < 0.05
    assert math.sqrt(sum(v * v for v in st["quaternion"])) == pytest.approx(1.0, abs=1e-5)
    assert max(abs(v) for v in st["position"]) < 0.05
    assert max(abs(v) for v in st["velocity"]) < 0.05
    # attitude (for older SITLs) and the quaternion describe the same orientation.
    r, p, y = euler_from_quat(*st["quaternion"])
    assert st["attitude"] == pytest.approx([r, p, y], abs=1e-5)
    home_yaw = math.radians(load_scenario("S1").home.heading_deg)
    assert math.remainder(y - home_yaw, 2 * math.pi) == pytest.approx(0.0, abs=0.02)
    assert phys.steps == 200


def test_full_throttle_climbs_in_ned(link):
    sitl, _, _, _ = link
    for _ in range(600):
        _, st = sitl.exchange(pwm=(2000, 2000, 2000, 2000, 1500, 1500))
    # NED: climbing is negative down position and negative down velocity; thrust pushes -z.
    assert st["position"][2] < -0.3
    assert st["velocity"][2] < -0.5
    assert st["accel_body"][2] < -10.0


def test_lockstep_duplicates_drops_and_reset(link):
    sitl, phys, _, notes = link
    for _ in range(10):
        raw, st = sitl.exchange()
    assert st["timestamp"] == pytest.approx(0.010, abs=1e-12)
    # A resend of the same frame (SITL's 1 s timeout): the same reply, no physics step.
    again, st2 = sitl.exchange(frame=sitl.frame)
    assert again == raw and phys.steps == 10 and phys.duplicates == 1
    # Lost packets: frame count jumps; exactly one step for the packet that arrived.
    sitl.frame += 5
    _, st3 = sitl.exchange()
    assert st3["timestamp"] == pytest.approx(0.011, abs=1e-12)
    assert phys.dropped_frames == 5
    # SITL restarts (frame count back to 1): physics restarts, its time goes back.
    sitl.frame = 0
    _, st4 = sitl.exchange()
    assert st4["timestamp"] == pytest.approx(0.001, abs=1e-12)
    assert st4["timestamp"] < st3["timestamp"] and phys.resets == 1
    assert any("restarted" in n for n in notes)


def test_32_channel_packets_and_rate_note(link):
    sitl, phys, _, notes = link
    _, st = sitl.exchange(channels=32, rate_hz=1200)
    assert st["timestamp"] == pytest.approx(0.001, abs=1e-12)
    assert phys.channels == 32 and phys.sitl_rate_hz == 1200
    assert any("SIM_RATE_HZ 1000" in n for n in notes)


def test_wrong_magic_is_refused_with_a_clear_message(link):
    sitl, _, box, _ = link
    sitl.send_raw(b"\x34\x12" + bytes(38))
    for _ in range(250):
        if "error" in box:
            break
        threading.Event().wait(0.02)
    err = box.get("error")
    assert isinstance(err, apj.ArduPilotProtocolError) and err.user_facing
    assert "magic 4660" in str(err) and "--model JSON" in str(err)


def test_decode_rejects_bad_sizes_and_clamps_pwm():
    with pytest.raises(apj.ArduPilotProtocolError, match="too short"):
        apj.decode_servo_packet(b"\x1a\x48")
    with pytest.raises(apj.ArduPilotProtocolError, match="expected 40"):
        apj.decode_servo_packet(apj.encode_servo_packet(1, [1000] * 4)[:-2])
    pkt = apj.decode_servo_packet(apj.encode_servo_packet(7, [0, 2500, 1500, 1000]))
    assert pkt.frame_count == 7 and pkt.magic == apj.MAGIC_16
    assert apj.motor_pwm_us(pkt) == (1000.0, 2000.0, 1500.0, 1000.0)
    assert apj.PACKET_16.size == 40 and apj.PACKET_32.size == 72
    assert apj.sitl_port(2) == 9022
    assert parse_address("10.0.0.2:9012", 9002) == ("10.0.0.2", 9012)
    assert parse_address(None, 9002) == ("127.0.0.1", 9002)


def test_silence_before_the_first_packet_says_how_to_start_sitl():
    sc = load_scenario("S1")
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    with JsonPhysicsServer(phys, ("127.0.0.1", 0)) as server:
        with pytest.raises(SitlLost, match="arducopter --model JSON"):
            server.serve(1.0, connect_timeout_s=0.1, poll_s=0.02)


@pytest.mark.parametrize("imu_hz", [4000, 500])
def test_oversampled_and_slow_imu_still_give_one_reply_per_step(imu_hz):
    """4 kHz: the step's four samples are averaged; 500 Hz: steps without a sample send truth."""
    sc = load_scenario("S1")
    phys = ArduPilotPhysics(lambda: Simulator(sc, imu_hz=imu_hz))
    for k in range(1, 101):
        st = sitl_read(phys.handle(apj.encode_servo_packet(k, [1000] * 4)).decode())
        assert st["accel_body"][2] == pytest.approx(-9.81, abs=0.4)
    assert st["timestamp"] == pytest.approx(0.1, abs=1e-12) and phys.steps == 100
