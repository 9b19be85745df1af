"""PX4's simulator contract, pinned by a recorded real exchange (no PX4 needed).

tests/tools/px4_exchange.json holds the first frames between PX4 v1.15.4 SITL and the bridge
(tests/tools/record_px4_exchange.py wrote it): PX4's opening messages, the freewheel start and
lockstep replies. These tests check the recording against the contract (so a re-recording
with another PX4 that breaks it shows up), then replay PX4's side of it, message for message,
against the real bridge server on a real Simulator over TCP, and check the bridge behaves as
it did with PX4: freewheels until the first reply, then steps exactly once per reply.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.autopilots.px4 import server as px4_server
from silbridge.bridge.autopilots.px4.server import Px4HilServer
from silbridge.bridge.errors import StartupCheckFailed
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.bridge.autopilots.px4 import hil_messages as px4_hil
from silbridge.mavlink.hil.hil_channel import make_codec

FIXTURE = Path(__file__).with_name("px4_exchange.json")


def _decode(hexes) -> list:
    codec = mav.MAVLink(None)
    codec.robust_parsing = True
    out = []
    for direction, h in hexes:
        msgs = codec.parse_buffer(bytes.fromhex(h)) or []
        assert len(msgs) == 1, f"one frame per event, got {msgs}"
        out.append((direction, msgs[0]))
    return out


@pytest.fixture(scope="module")
def recording():
    data = json.loads(FIXTURE.read_text())
    return data, _decode(data["events"])


def test_px4_opens_with_its_state_interval_request_and_a_heartbeat(recording):
    _, events = recording
    first_tx = next(i for i, (d, _) in enumerate(events) if d == "tx")
    opening = [m for d, m in events[:first_tx] if d == "rx"]
    kinds = {m.get_type(): m for m in opening}
    assert kinds["HEARTBEAT"].autopilot == px4_hil.PX4_AUTOPILOT
    cmd = kinds["COMMAND_LONG"]
    assert cmd.command == px4_hil.CMD_SET_MESSAGE_INTERVAL
    assert cmd.param1 == px4_hil.MSG_HIL_STATE_QUATERNION and cmd.param2 == 5000


def test_freewheel_then_one_reply_per_step_on_the_sim_clock(recording):
    data, events = recording
    step_us = data["step_us"]
    sensor_times = []
    replies = []          # (reply time_usec, newest HIL_SENSOR time before it, sensors so far)
    for d, m in events:
        t = m.get_type()
        if d == "tx" and t == "HIL_SENSOR":
            sensor_times.append(m.time_usec)
        elif d == "rx" and t == "HIL_ACTUATOR_CONTROLS":
            replies.append((m.time_usec, sensor_times[-1], len(sensor_times), m))
    # The sim clock: one PX4 step per HIL_SENSOR, time_usec from the first step on.
    assert sensor_times == [step_us * (k + 1) for k in range(len(sensor_times))]
    # Freewheel: PX4 answers only after several steps of sim time (its estimator and logger
    # must run first); the bridge kept sending meanwhile.
    first = replies[0]
    assert first[2] == data["freewheel_steps"] >= 5
    # Lockstep: every reply carries the newest sensor time (PX4's clock) and the lockstep
    # flag; after the first, exactly one new HIL_SENSOR between consecutive replies.
    assert len(replies) >= 50
    for t_reply, t_sensor, _, m in replies:
        assert t_reply == t_sensor
        assert m.flags & px4_hil.FLAG_LOCKSTEP
        assert not m.mode & px4_hil.MODE_ARMED and max(m.controls) == 0.0   # disarmed
    counts = [r[2] for r in replies]
    assert all(b - a == 1 for a, b in zip(counts, counts[1:]))


def test_bridge_sensors_use_px4_field_groups_and_interval(recording):
    _, events = recording
    sensors = [m for d, m in events if d == "tx" and m.get_type() == "HIL_SENSOR"]
    groups = (px4_hil.FIELDS_ACCEL, px4_hil.FIELDS_GYRO, px4_hil.FIELDS_MAG,
              px4_hil.FIELDS_BARO)
    assert (px4_hil.FIELDS_ACCEL, px4_hil.FIELDS_GYRO, px4_hil.FIELDS_MAG,
            px4_hil.FIELDS_BARO) == (0b111, 0b111000, 0b111000000, 0b1101000000000)
    for m in sensors:
        assert m.id == 0
        bits = m.fields_updated
        for g in groups:             # PX4 takes a group only when all its bits are set
            assert bits & g in (0, g)
        assert bits & (px4_hil.FIELDS_ACCEL | px4_hil.FIELDS_GYRO) == 0b111111
        assert abs(m.zacc + 9.8) < 0.5                     # on the ground
    baro = [m for m in sensors if m.fields_updated & px4_hil.FIELDS_BARO]
    mag = [m for m in sensors if m.fields_updated & px4_hil.FIELDS_MAG]
    span_s = (sensors[-1].time_usec - sensors[0].time_usec) / 1e6
    assert len(baro) == pytest.approx(100 * span_s, abs=2)     # the scenario's 100 Hz
    assert len(mag) == pytest.approx(100 * span_s, abs=2)
    # Not perfectly noise-free (PX4 flags a frozen sensor STALE and refuses to arm); the
    # pressure is on the 1/128 hPa grid HIL_SENSOR carries exactly (mavlink/hil/hil_quant.py).
    assert len({m.abs_pressure for m in baro}) >= 4
    assert len({m.xmag for m in mag}) > len(mag) // 2
    for m in baro:
        assert m.pressure_alt == pytest.approx(px4_hil.pressure_altitude_m(m.abs_pressure * 100),
                                               abs=0.01)
    states = [m.time_usec for d, m in events if d == "tx"
              and m.get_type() == "HIL_STATE_QUATERNION"]
    assert all(b - a >= 5000 for a, b in zip(states, states[1:]))   # PX4's 5000 us request
    gps = [m for d, m in events if d == "tx" and m.get_type() == "HIL_GPS"]
    assert gps and all(m.fix_type == 3 and m.satellites_visible >= 6 and m.eph <= 300
                       for m in gps)


class _FakePx4(threading.Thread):
    """PX4's side of the recording replayed: each recorded PX4 message goes out once the bridge
    has sent as many HIL_SENSOR as PX4 had received before it; HIL_ACTUATOR_CONTROLS carry
    the newest sensor time received, as PX4's clock would.

    extra_s: after the recording (0.4 s of sim time), keep answering each HIL_SENSOR with the
    last recorded reply for this much more sim time, so the bridge reaches its start-up check
    (STARTUP_CHECK_S after the first reply); lockstep=False clears the lockstep flag in those
    replies, as a PX4 built without lockstep sends them."""

    def __init__(self, port: int, events, extra_s: float = 0.0, lockstep: bool = True):
        super().__init__(daemon=True)
        self.port = port
        self.script = []
        seen = 0
        for d, m in events:
            if d == "tx" and m.get_type() == "HIL_SENSOR":
                seen += 1
            elif d == "rx":
                self.script.append((seen, m))
        answered, last = next((n, m) for n, m in reversed(self.script)
                              if m.get_type() == "HIL_ACTUATOR_CONTROLS")
        step_us = 4000           # the recording's HIL_SENSOR spacing (checked by the test below)
        for k in range(1, int(extra_s * 1e6 / step_us) + 1):
            m = mav.MAVLink_hil_actuator_controls_message(
                0, list(last.controls), last.mode,
                last.flags if lockstep else last.flags & ~px4_hil.FLAG_LOCKSTEP)
            self.script.append((answered + k, m))
        # The recording may end with HIL_SENSORs PX4 had not answered yet: the added replies
        # answer them, in order (a stable sort keeps the recorded order otherwise).
        self.script.sort(key=lambda e: e[0])
        self.codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
        self.sensor_times: list = []
        self.error = None

    def run(self) -> None:
        try:
            s = socket.create_connection(("127.0.0.1", self.port), timeout=10)
            s.settimeout(10)
            rx = mav.MAVLink(None)
            rx.robust_parsing = True
            for need, m in self.script:
                while len(self.sensor_times) < need:
                    data = s.recv(65536)
                    if not data:         # the bridge closed the link before the script's end
                        s.close()
                        return
                    for got in rx.parse_buffer(data) or []:
                        if got.get_type() == "HIL_SENSOR":
                            self.sensor_times.append(got.time_usec)
                if m.get_type() == "HIL_ACTUATOR_CONTROLS":
                    m.time_usec = self.sensor_times[-1]
                s.sendall(m.pack(self.codec))
            while s.recv(65536):      # until the bridge closes the link
                pass
            s.close()
        except (ConnectionResetError, BrokenPipeError):
            pass      # the bridge closed the link while replies were still going out: its end
        except Exception as e:  # noqa: BLE001 - reported by the test
            self.error = repr(e)


def test_bridge_freewheels_then_steps_once_per_replayed_px4_reply(recording):
    data, events = recording
    phys = Px4Physics(lambda: Simulator(load_scenario("S1", seed=1)), make_codec(1, 51))
    replies = sum(1 for d, m in events if d == "rx"
                  and m.get_type() == "HIL_ACTUATOR_CONTROLS")
    with Px4HilServer(phys, ("127.0.0.1", 0)) as server:
        fake = _FakePx4(server.address[1], events)
        fake.start()
        res = server.serve(30.0, connect_timeout_s=10.0, stall_s=0.5, idle_timeout_s=10.0,
                           stop=lambda: phys.replies >= replies)
    fake.join(10)
    assert fake.error is None
    st = res.stats
    assert st["replies"] == replies and st["unanswered_steps"] == 0
    assert st["px4_lockstep_flag"] is True
    # The freewheel lasted until the first reply: the fake sends it after the recorded number
    # of steps; on a busy machine the bridge may have freewheeled a few more meanwhile, and
    # then that first reply is stale (it answers an older step: no step is made for it).
    assert st["freewheel_steps"] >= data["freewheel_steps"]
    assert st["stale_replies"] <= 1 and st["answered"] + st["stale_replies"] == replies
    # Then exactly one step per answer.
    assert st["px4_steps"] == st["freewheel_steps"] + st["answered"]
    assert st["state_interval_us"] == 5000
    assert fake.sensor_times == [4000 * (k + 1) for k in range(len(fake.sensor_times))]
    # 0.4 s of sim time: the start-up check (2 s after the first reply) has not run yet; the
    # two tests below replay long enough to reach it.
    assert res.startup_check == {}


def _freewheel_steps(realtime: bool, wall_s: float = 0.4) -> int:
    """Steps the server freewheels in wall_s to a PX4 that connects and never answers."""
    phys = Px4Physics(lambda: Simulator(load_scenario("S1", seed=1)), make_codec(1, 51))
    with Px4HilServer(phys, ("127.0.0.1", 0)) as server:
        px4 = socket.create_connection(server.address, timeout=10)

        def read_until_closed():
            while px4.recv(65536):
                pass
        reader = threading.Thread(target=read_until_closed, daemon=True)
        reader.start()
        t_end = time.monotonic() + wall_s
        res = server.serve(30.0, realtime=realtime, connect_timeout_s=10.0,
                           idle_timeout_s=10.0, stop=lambda: time.monotonic() >= t_end)
    reader.join(10)      # the server closed the link: the reader's recv returned b""
    px4.close()
    return res.stats["freewheel_steps"]


def test_a_booting_px4_is_freewheeled_at_the_same_pace_in_real_time():
    """Until PX4's first reply the server steps at FREEWHEEL_WALL_S in real time as in
    lockstep, not at the step period: freewheeled at the step period, most real-time boots
    of PX4 v1.15 started EKF2 with a vertical velocity at rest (server.py's docstring)."""
    lockstep, realtime = _freewheel_steps(False), _freewheel_steps(True)
    # at the step period (4 ms) it would be about a quarter of lockstep's (1 ms)
    assert realtime > 0.6 * lockstep, (realtime, lockstep)


def _serve_until_checked(events, lockstep: bool):
    phys = Px4Physics(lambda: Simulator(load_scenario("S1", seed=1)), make_codec(1, 51))
    fake = None
    try:
        with Px4HilServer(phys, ("127.0.0.1", 0)) as server:
            fake = _FakePx4(server.address[1], events, extra_s=px4_server.STARTUP_CHECK_S + 0.5,
                            lockstep=lockstep)
            fake.start()
            return server.serve(30.0, connect_timeout_s=10.0, stall_s=0.5, idle_timeout_s=10.0,
                                stop=lambda: bool(server.check))
    finally:     # the server has closed the link: the fake's read loop ends
        if fake is not None:
            fake.join(10)
            assert fake.error is None


def test_px4_start_up_check_passes_on_a_lockstep_replay_long_enough_to_reach_it(recording):
    _, events = recording
    res = _serve_until_checked(events, lockstep=True)
    check = res.startup_check
    assert check["passed"] is True and "problems" not in check
    assert check["after_sim_s"] >= px4_server.STARTUP_CHECK_S
    assert check["px4_lockstep_flag"] is True
    assert check["unanswered"] == 0 and check["bad_crc"] == 0 and check["malformed"] == 0
    assert check["replies"] == res.stats["replies"] > 0


def test_px4_start_up_check_fails_when_px4_drops_the_lockstep_flag(recording):
    _, events = recording
    with pytest.raises(StartupCheckFailed, match="lack the lockstep flag"):
        _serve_until_checked(events, lockstep=False)


def test_controls_map_px4_outputs_to_our_motors():
    # PX4 output i (rotor i of 10016_none_iris) drives our motor i + 1; 0..1 -> 1000..2000 us.
    assert px4_hil.controls_to_pwm_us([0.0, 0.25, 0.5, 1.0] + [0.0] * 12) == [1000, 1250, 1500,
                                                                                2000]
    assert px4_hil.controls_to_pwm_us([-0.5, 1.5, float("nan"), 0.1] + [0.0] * 12) == \
        [1000, 2000, 1000, 1100]


def _env_without_px4() -> dict:
    env = dict(os.environ)
    env.pop("SILBRIDGE_PX4", None)
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    return env


def test_bench_fc_px4_without_a_binary_says_how_to_build_one(tmp_path):
    p = subprocess.run([sys.executable, "-m", "silbridge.tools", "bench", "--fc", "px4",
                        "--scenarios", "S1", "--runs", "1", "--json", "--out",
                        str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=60, env=_env_without_px4())
    assert p.returncode == 2 and p.stdout == "" and not (tmp_path / "out").exists()
    assert "SILBRIDGE_PX4" in p.stderr and "make px4_sitl_default" in p.stderr
    p = subprocess.run([sys.executable, "-m", "silbridge.tools", "bench", "--fc", "px4",
                        "--px4", str(tmp_path / "nope"), "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=60, env=_env_without_px4())
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert "make px4_sitl_default" in p.stderr


def _realtime_check_after(rates_hz: list[float]) -> Px4HilServer:
    """Drive the start-up check as the real-time loop does, PX4 replying at rates_hz[k] in
    the k-th second after its first reply (counters only: the check reads nothing else)."""
    rx = SimpleNamespace(rx_bad_crc=0, rx_malformed=0)
    phys = SimpleNamespace(first_reply_us=0, last_sent_us=0, replies=0, steps=0,
                           freewheel_steps=0, unanswered=0, lockstep_flag=False, step_hz=250)
    server = Px4HilServer(phys, channel=SimpleNamespace(rx=rx, close=lambda: None))
    for second, hz in enumerate(rates_hz):
        for k in range(250):
            phys.last_sent_us = int((second + (k + 1) / 250) * 1e6)
            phys.steps += 1
            phys.replies = int(sum(rates_hz[:second]) + hz * (k + 1) / 250)
            server._startup_check(realtime=True)
            if server.check:
                return server
    return server


def test_px4_real_time_check_forgives_a_slow_boot_but_not_a_slow_px4():
    # PX4 booting on a busy machine: 2 s at 150 Hz, then its 250 Hz. Passes on a later window.
    server = _realtime_check_after([150, 150, 250, 250, 250])
    assert server.check["passed"] is True and server.check["reply_hz"] >= 225
    assert server.check["after_sim_s"] >= 2 * px4_server.STARTUP_CHECK_S
    # A PX4 running at 160 Hz never passes a window: the check fails at STARTUP_CHECK_MAX_S.
    with pytest.raises(StartupCheckFailed, match="PX4 answered at 160 Hz"):
        _realtime_check_after([160] * 12)
