"""`silbridge bench --fc ardupilot` and `silbridge bridge --fc ardupilot` without and with SITL.

Always run: no binary (an error before any run, saying how to get one), the
`bridge --fc ardupilot` command against a fake SITL, the bridge-side log of an
ArduCopter flight (setpoints forwarded, JSON link timed) through the real
integrity check and metrics, the setpoint forwarder's altitude and retry
rules, the SITL defaults, the MAVLink driver (GUIDED, arm, take-off, reported
target and altitude, SET_ATTITUDE_TARGET from another thread) against a fake
ArduCopter MAVLink port, and whole bench runs with a stand-in `arducopter`
executable (fake_arducopter.py: same command line, ports and protocols, a
plain altitude hold, a report of the SET_ATTITUDE_TARGET it received). With
SILBRIDGE_ARDUCOPTER pointing at an arducopter binary, an end-to-end run
arms, takes off and hovers for 30 s of sim time on our physics.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.tools.autopilots.ardupilot.driver import COPTER_MODE_GUIDED, MavlinkDriver
from silbridge.tools.autopilots.ardupilot.setpoints import (ArduCopterSetpointForwarder,
                                                            thrust_for_climb)
from silbridge.tools.autopilots.ardupilot.sitl import find_arducopter, sitl_defaults, write_defaults
from silbridge.tools.autopilots.common.flight import BenchStepHooks
from silbridge.tools.autopilots.common.log_sink import (SOURCE_ATTITUDE_TARGET, AttitudeTarget,
                                                        AutopilotLogSink)
from silbridge.tools.benchmark.metrics import Windows, compute_metrics
from silbridge.tools.logs.integrity import check_log
from silbridge.tools.logs.mcap_log import read_log

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import free_udp_port  # noqa: E402

CLI = [sys.executable, "-m", "silbridge.tools"]


def _env_without_sitl(tmp_path) -> dict:
    env = dict(os.environ)
    env.pop("SILBRIDGE_ARDUCOPTER", None)
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    return env


def test_bench_without_binary_is_an_error_that_says_how_to_get_one(tmp_path):
    env = _env_without_sitl(tmp_path)
    if shutil.which("arducopter", path=env["PATH"]):
        pytest.skip("an arducopter binary is in /usr/bin here: no binary cannot be shown")
    p = subprocess.run(CLI + ["bench", "--fc", "ardupilot", "--scenarios", "S1", "--runs", "1",
                              "--duration", "4", "--out", str(tmp_path / "out"), "--json"],
                       capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr and p.stdout == ""
    assert "SILBRIDGE_ARDUCOPTER" in p.stderr and "waf" in p.stderr
    assert not (tmp_path / "out").exists()      # refused before any run


def test_bench_with_a_missing_binary_is_a_user_error(tmp_path):
    p = subprocess.run(CLI + ["bench", "--fc", "ardupilot", "--arducopter", str(tmp_path / "nope"),
                              "--scenarios", "S1", "--runs", "1", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2
    assert "Traceback" not in p.stderr and "./waf copter" in p.stderr


def test_bench_refuses_an_unknown_fc(tmp_path):
    p = subprocess.run(CLI + ["bench", "--fc", "betaflight", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "--fc wants" in p.stderr


def test_bridge_command_serves_a_fake_sitl():
    port = free_udp_port()
    proc = subprocess.Popen(CLI + ["bridge", "--fc", "ardupilot", "--link-addr",
                                   f"127.0.0.1:{port}", "--duration", "0.2", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    sitl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sitl.settimeout(0.2)
    try:
        frame, replies, t_end = 0, [], time.monotonic() + 30
        while len(replies) < 200 and time.monotonic() < t_end:
            sitl.sendto(apj.encode_servo_packet(frame + 1, [1000] * 4), ("127.0.0.1", port))
            try:
                replies.append(json.loads(sitl.recv(65536)))
                frame += 1
            except (socket.timeout, ConnectionRefusedError):
                continue   # the bridge is still starting: resend the same frame
        out, err = proc.communicate(timeout=30)
    finally:
        sitl.close()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert replies[-1]["timestamp"] == pytest.approx(0.2)
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["fc"] == "ardupilot" and summary["json_link"]["steps"] == 200
    assert summary["sim_s"] == pytest.approx(0.2)


def _short_s4(start_s: float = 1.0):
    """S4 with one roll doublet from start_s (amplitude and hold drawn from S4's seed)."""
    return load_scenario("S4", overrides={"setpoint[0].start_s": start_s, "setpoint[0].repeat": 1,
                                          "setpoint[1].start_s": 60.0, "setpoint[1].repeat": 1})


def _roll_pitch_yaw(q):
    from silbridge.bridge.frames import euler_from_quat
    return euler_from_quat(*q)


def test_bridge_side_log_forwards_the_profile_and_logs_timing(tmp_path):
    """Physics + forwarder + log sink as a bench run wires them, fed by servo packets the
    way the UDP server feeds them (arrival time in, `sent` after the reply)."""
    sc = _short_s4()
    amp_rad = math.radians(sc.setpoints[0].amplitude_deg[0])
    target = AttitudeTarget()
    sent, alt = [], {"m": None}
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    fwd = ArduCopterSetpointForwarder(sc, phys.sim.dt_ns, math.radians(sc.home.heading_deg),
                            send=lambda *a: sent.append((phys.sim.sim_ns, *a)) or True,
                            reported_alt_m=lambda: alt["m"])
    meta = {"config": {"imu_hz": phys.sim.imu_hz, "pwm_hz": 1000.0, "physics_hz": 1000.0,
                       "baro_hz": sc.baro_hz, "mag_hz": sc.mag_hz, "gnss_hz": sc.gnss_hz,
                       "duration_s": 2.5, "seed": sc.seed},
            "params": {"MOT_PWM_MIN": 1000, "MOT_PWM_MAX": 2000}}
    path = tmp_path / "ap.mcap"
    sink = AutopilotLogSink(path, metadata=meta, target=target, duration_s=2.5, command=fwd)
    hooks = phys.sink = BenchStepHooks(fwd, sink)
    frame = 0
    while not sink.done:
        frame += 1
        if frame in (300, 500):                   # take-off commands sent at 0.299, 0.499 s
            hooks.takeoff_sent(phys.sim.sim_ns)
        if frame == 620:                          # the second one's ACK read 0.12 s later
            hooks.takeoff_accepted()
        if frame == 800:                          # ArduCopter reports the take-off altitude
            alt["m"] = sc.takeoff_alt_m + 0.2
            target.set(0.02, -0.01, 0.0, SOURCE_ATTITUDE_TARGET)
        phys.handle(apj.encode_servo_packet(frame, [1400] * 4), None, time.monotonic_ns())
        phys.sent(time.monotonic_ns())
    sink.close()
    t0 = 499_000_000                              # the physics time of the take-off command
    # Nothing is sent during the take-off; from the reported altitude on, at >= 20 Hz.
    assert fwd.engaged_by == "altitude" and fwd.engaged_ns == pytest.approx(0.3e9, abs=2e6)
    times = np.array([s[0] for s in sent]) - t0
    assert times[0] == pytest.approx(0.3e9, abs=2e6) and np.diff(times).max() <= 50_000_000
    assert all(s[3] == 0.5 and s[4] == 0b111 for s in sent)   # hold altitude; rates ignored
    q = np.array([s[2] for s in sent])
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    rolls = np.array([_roll_pitch_yaw(qi)[0] for qi in q])
    assert rolls.max() == pytest.approx(amp_rad, abs=1e-6)   # the doublet's +A went out
    assert rolls[times < 1.0e9].max() == 0.0                   # and not before its start
    # While the roll ramps (0.5 s), every 20 ms setpoint step is sent at once.
    ramp = (times > 1.0e9) & (times < 1.5e9)
    assert np.diff(times[ramp]).max() <= 21_000_000

    log = read_log(path)
    assert check_log(log) == []
    # Time 0 is the accepted command's send, not its ACK: the steps between were held.
    assert sink.t0_ns == t0 and log.events[0]["fields"]["physics_sim_ns"] == t0
    st = log.channels["/fc/status"]
    assert st["sim_ns"][0] == 0 and len(st) == 2500 and (np.diff(st["sim_ns"]) == 1e6).all()
    assert len(log.channels["/pwm"]) == 2500 and log.channels["/imu"]["sim_ns"][0] >= 0
    # The motor model's rotor speeds, one row per physics step on the log clock (/rotor).
    rot = log.channels["/rotor"]
    np.testing.assert_array_equal(rot["sim_ns"], st["sim_ns"] + 1_000_000)
    assert rot["omega_rad_s"].shape == (2500, 4) and (rot["omega_rad_s"][-1] > 300).all()
    # The command as forwarded, on the log clock: what the "cmd" scoring reads.
    sp = log.channels["/setpoint"]
    assert sp["sim_ns"][0] == 0 and sp["roll_rad"].max() == pytest.approx(amp_rad, rel=1e-6)
    assert len(sp) < len(st) and (np.diff(sp["sim_ns"]) > 0).all()
    # The metrics' command is what was sent, on the physics clock.
    assert st["att_target_rad"][:, 0].max() == pytest.approx(amp_rad, rel=1e-6)
    i_ramp = np.searchsorted(st["sim_ns"], int(1.25e9))
    assert st["att_target_rad"][i_ramp, 0] == pytest.approx(amp_rad / 2, abs=0.03)
    assert st["forwarding"][:299].max() == 0 and st["forwarding"][301:].min() == 1
    assert np.isnan(st["ap_target_rad"][:299]).all()            # nothing reported yet
    assert st["ap_target_rad"][-1, 0] == pytest.approx(0.02) and st["target_source"][-1] == 1
    m = compute_metrics(log, Windows(warmup=(0, 0.5), transient=(0.5, 1.0),
                                     analysis=(1.0, 2.5), yaw=(2.0, 2.5)))
    # The vehicle stays level on the ground: the error is the command itself.
    win = (st["sim_ns"] >= 1.0e9) & (st["sim_ns"] <= 2.5e9)
    cmd_deg = np.degrees(np.hypot(st["att_target_rad"][win, 0], st["att_target_rad"][win, 1]))
    assert m["att_rms_deg"] == pytest.approx(np.sqrt(np.mean(cmd_deg ** 2)), abs=0.3)
    # One /timing row per servo packet: physics latency and SITL's frame period.
    tim = log.channels["/timing"]
    assert len(tim) == 2500 and tim["sim_ns"][0] == 0
    assert (tim["pwm_wall_ns"] >= tim["consume_wall_ns"]).all()
    assert (tim["consume_wall_ns"] >= tim["imu_wall_ns"]).all()
    assert (tim["loop_period_ns"][1:] > 0).all()
    assert 0 < m["latency_ms"] < 50 and math.isfinite(m["jitter_ms"])
    assert m["loop_period_ms"] > m["latency_ms"]


def test_forwarder_flies_altitude_through_the_thrust_field():
    sc = load_scenario("S1")
    sent, alt = [], {"m": None}
    fwd = ArduCopterSetpointForwarder(sc, 1_000_000, 0.0, send=lambda *a: sent.append(a) or True,
                            reported_alt_m=lambda: alt["m"])
    fwd.step(5_000_000)                      # before take-off: nothing
    fwd.start_at(5_000_000)
    for k in range(1, 3000):                 # no report, profile constant: wait
        fwd.step(5_000_000 + k * 1_000_000)
    assert not sent and not fwd.engaged
    alt["m"] = sc.takeoff_alt_m - 0.45      # inside the engage margin, outside the deadband
    fwd.step(5_000_000 + 3000 * 1_000_000)
    assert fwd.engaged_by == "altitude"
    assert sent[-1][2] == pytest.approx(0.5 + 0.5 * 0.5 * 0.45 / 2.5)   # climb 0.225 m/s
    assert thrust_for_climb(0.0) == 0.5 and thrust_for_climb(10.0) == 1.0
    assert thrust_for_climb(-0.75) == pytest.approx(0.25) and thrust_for_climb(-9.0) == 0.0
    # A link that is not up yet: counted, retried at the next step, not every 50 ms.
    fails = ArduCopterSetpointForwarder(sc, 1_000_000, 0.0, send=lambda *a: False,
                              reported_alt_m=lambda: None)
    fails.start_at(0)
    for k in range(1, 10_003):
        fails.step(k * 1_000_000)
    assert fails.engaged_by == "timeout" and fails.refused == 3 and fails.sent == 0


def test_sitl_defaults_match_our_quad_x(tmp_path):
    sim = Simulator(load_scenario("S1"))
    d = sitl_defaults(sim, 1000.0, {"ATC_RAT_RLL_P": 0.12})
    assert d["FRAME_CLASS"] == 1 and d["FRAME_TYPE"] == 1 and d["SIM_RATE_HZ"] == 1000
    assert (d["MOT_PWM_MIN"], d["MOT_PWM_MAX"]) == (1000, 2000)
    assert d["ANGLE_MAX"] >= 3500          # S4's 35 deg tilts are not scaled down
    assert d["MOT_THST_HOVER"] == pytest.approx(sim.hover_throttle, abs=1e-4)
    write_defaults(str(tmp_path / "d.parm"), d)
    lines = (tmp_path / "d.parm").read_text().splitlines()
    assert "FRAME_CLASS 1" in lines and "ATC_RAT_RLL_P 0.12" in lines


class FakeArduCopter(threading.Thread):
    """ArduCopter's MAVLink TCP port, reduced to what the driver needs."""

    def __init__(self):
        super().__init__(daemon=True)
        self.listener = socket.socket()
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(1)
        self.port = self.listener.getsockname()[1]
        self.mode, self.armed, self.takeoff_alt = 0, False, None
        self.intervals = {}
        self.attitude_targets = []
        self.stop = threading.Event()

    def write(self, buf):
        self.conn.sendall(buf)

    def run(self):
        self.conn, _ = self.listener.accept()
        self.conn.settimeout(0.02)
        codec = mav.MAVLink(self, srcSystem=1, srcComponent=1)
        next_beat = 0.0
        while not self.stop.is_set():
            if time.monotonic() > next_beat:
                base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
                    mav.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
                codec.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                     base, self.mode, mav.MAV_STATE_STANDBY)
                if self.takeoff_alt is not None:
                    codec.attitude_target_send(0, 0, [math.cos(0.05), math.sin(0.05), 0, 0],
                                               0, 0, 0, 0.5)
                    codec.global_position_int_send(0, 0, 0, 0, 9_750, 0, 0, 0, 0)
                next_beat = time.monotonic() + 0.05
            try:
                data = self.conn.recv(4096)
            except socket.timeout:
                continue
            if not data:
                return
            for m in codec.parse_buffer(data) or []:
                if m.get_type() == "SET_ATTITUDE_TARGET":
                    self.attitude_targets.append(m)
                if m.get_type() != "COMMAND_LONG":
                    continue
                if m.command == mav.MAV_CMD_DO_SET_MODE:
                    self.mode = int(m.param2)
                elif m.command == mav.MAV_CMD_COMPONENT_ARM_DISARM:
                    self.armed = m.param1 == 1
                elif m.command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
                    self.intervals[int(m.param1)] = m.param2
                elif m.command == mav.MAV_CMD_NAV_TAKEOFF:
                    self.takeoff_alt = m.param7
                codec.command_ack_send(m.command, mav.MAV_RESULT_ACCEPTED)

    def close(self):
        self.stop.set()
        self.join(2)
        self.listener.close()


def test_mavlink_driver_sets_guided_arms_takes_off_and_reads_the_target():
    fake = FakeArduCopter()
    fake.start()
    target = AttitudeTarget()
    took_off = threading.Event()
    t0 = time.monotonic()
    # Sim time runs 100x the wall clock here, like a fast lockstep SITL.
    drv = MavlinkDriver(0, takeoff_alt_m=10.0, sim_time_s=lambda: 100 * (time.monotonic() - t0),
                        on_takeoff=took_off.set, target=target, connect_timeout_s=5)
    drv.addr = ("127.0.0.1", fake.port)
    drv.start()
    try:
        assert took_off.wait(10), f"no take-off: {drv.error} mode={fake.mode} armed={fake.armed}"
        deadline = time.monotonic() + 5
        while (target.get()[1] != SOURCE_ATTITUDE_TARGET or drv.reported_alt_m() is None) \
                and time.monotonic() < deadline:
            time.sleep(0.01)
        # The physics thread's sends share the link with the driver's own (one lock).
        q = (math.cos(0.1), math.sin(0.1), 0.0, 0.0)
        for k in range(20):
            assert drv.send_attitude_target(1000 + k, q, 0.5, 0b111)
        deadline = time.monotonic() + 5
        while len(fake.attitude_targets) < 20 and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        drv.stop()
        fake.close()
    assert drv.error is None
    assert fake.mode == COPTER_MODE_GUIDED and fake.armed and fake.takeoff_alt == 10.0
    assert fake.intervals[mav.MAVLINK_MSG_ID_ATTITUDE_TARGET] == pytest.approx(20000)
    (roll, pitch, _), source = target.get()
    assert source == SOURCE_ATTITUDE_TARGET and roll == pytest.approx(0.1, abs=1e-6)
    assert drv.reported_alt_m() == pytest.approx(9.75)
    assert fake.intervals[mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT] == pytest.approx(100000)
    got = fake.attitude_targets
    assert [m.time_boot_ms for m in got] == list(range(1000, 1020))
    assert all(m.type_mask == 0b111 and m.thrust == 0.5 and m.target_system == 1 for m in got)
    assert got[0].q[1] == pytest.approx(math.sin(0.1))


@pytest.mark.skipif(not os.environ.get("SILBRIDGE_ARDUCOPTER"),
                    reason="set SILBRIDGE_ARDUCOPTER to an arducopter SITL binary to fly it "
                           "end to end (none on this machine; see docs/tutorials/arducopter-and-px4.md)")
def test_arducopter_arms_takes_off_and_hovers_30_s(tmp_path):
    from silbridge.tools.benchmark.campaign import make_specs, run_one

    spec = make_specs(["S1"], 1, 30.0, tmp_path, fc="ardupilot",
                      sitl=find_arducopter(), variant="ardupilot",
                      windows=((0.0, 10.0), (10.0, 20.0), (20.0, 30.0), (20.0, 30.0)))[0]
    r = run_one(spec)
    assert r.problems == []
    assert not r.summary["crashed"]
    assert r.summary["sim_s"] == pytest.approx(30.0, abs=0.01)
    log = read_log(spec.log_path)
    nav = log.channels["/gt_nav"]
    alt_m = -nav["pos_ned_m"][nav["sim_ns"] >= 20e9][:, 2]
    assert abs(alt_m.mean() - 10.0) < 1.0        # thrust 0.5 holds the take-off altitude
    assert math.isfinite(r.metrics["att_rms_deg"]) and r.metrics["att_rms_deg"] < 5.0
    for k in ("att_rms_cmd_deg", "att_p95_cmd_deg", "att_rms_target_deg", "att_p95_target_deg"):
        assert math.isfinite(r.metrics[k]) and r.metrics[k] < 5.0, k
    # The level command went out once ArduCopter reported the take-off altitude, and it
    # answered with its own target; the JSON link was timed.
    assert r.summary["forwarding_started_by"] == "altitude" and r.summary["setpoints_sent"] > 100
    st = log.channels["/fc/status"]
    assert (st["target_source"][st["sim_ns"] >= 20e9] == SOURCE_ATTITUDE_TARGET).all()
    assert math.isfinite(r.metrics["latency_ms"]) and math.isfinite(r.metrics["jitter_ms"])


@pytest.mark.skipif(not os.environ.get("SILBRIDGE_ARDUCOPTER"),
                    reason="set SILBRIDGE_ARDUCOPTER to an arducopter SITL binary to fly S4's "
                           "doublets end to end (none on this machine)")
def test_arducopter_flies_the_s4_roll_doublet(tmp_path):
    from silbridge.tools.benchmark.campaign import make_specs, run_one

    spec = make_specs(["S4"], 1, 17.0, tmp_path, fc="ardupilot", sitl=find_arducopter(),
                      variant="ardupilot",
                      windows=((0.0, 10.0), (10.0, 17.0), (10.0, 17.0), (10.0, 17.0)))[0]
    r = run_one(spec)
    assert r.problems == [] and not r.summary["crashed"]
    assert r.summary["forwarding_started_by"] == "altitude"
    amp_rad = math.radians(load_scenario("S4", seed=spec.seed).setpoints[0].amplitude_deg[0])
    log = read_log(spec.log_path)
    st = log.channels["/fc/status"]
    assert st["att_target_rad"][:, 0].max() == pytest.approx(amp_rad, rel=1e-5)
    # ArduCopter's own (shaped) target and the true roll follow the command.
    assert np.nanmax(st["ap_target_rad"][:, 0]) > 0.8 * amp_rad
    from silbridge.tools.benchmark.metrics import roll_pitch_from_quat
    roll, _ = roll_pitch_from_quat(log.channels["/gt_att"]["q_wxyz"])
    assert roll.max() > 0.7 * amp_rad and roll.min() < -0.7 * amp_rad
    # Scored both ways: its controller tracks its own shaped target (ATTITUDE_TARGET at
    # 50 Hz of sim time, placed by its stamps) closely; the raw command, which its input
    # shaping smooths, it trails by degrees.
    tg = log.channels["/fc/target"]
    assert (np.diff(np.sort(tg["fc_time_ns"])) <= 20_000_000).mean() > 0.95
    m = r.metrics
    assert m["att_rms_target_deg"] < 1.5 and m["att_p95_target_deg"] < 2.5
    assert m["att_rms_cmd_deg"] > 2.0 * m["att_rms_target_deg"] and m["att_rms_cmd_deg"] > 1.5
    assert m["att_rms_deg"] == m["att_rms_cmd_deg"]
    assert r.metrics["realtime_factor"] > 0


@pytest.fixture
def fake_sitl_binary(tmp_path) -> str:
    """An executable `arducopter` that is tests/tools/fake_arducopter.py."""
    path = tmp_path / "arducopter"
    script = Path(__file__).with_name("fake_arducopter.py")
    path.write_text(f"#!/bin/sh\nexec {sys.executable} {script} \"$@\"\n")
    path.chmod(0o755)
    return str(path)


def test_bench_run_with_a_stand_in_sitl_logs_from_take_off(tmp_path, fake_sitl_binary):
    """run_one --fc ardupilot end to end: process, ports, MAVLink driving, log, metrics."""
    from silbridge.tools.benchmark.campaign import make_specs, run_one

    spec = make_specs(["S1"], 1, 6.0, tmp_path, fc="ardupilot", sitl=fake_sitl_binary,
                      variant="ardupilot",
                      windows=((0.0, 2.0), (2.0, 3.0), (3.0, 6.0), (3.0, 6.0)))[0]
    r = run_one(spec)
    assert r.problems == []
    assert r.summary["fc"] == "ardupilot" and not r.summary["crashed"]
    assert r.summary["sim_s"] == pytest.approx(6.0, abs=0.002)
    assert r.summary["takeoff_physics_s"] >= 3.0       # the stand-in refuses to arm before 3 s
    log = read_log(spec.log_path)
    assert log.channels["/pwm"]["sim_ns"][0] == 0      # the log's clock starts at take-off
    up_m = -log.channels["/gt_nav"]["pos_ned_m"][:, 2]
    assert up_m[0] < 0.2 and up_m.max() > 2.0           # it left the ground under our physics
    assert math.isfinite(r.metrics["att_rms_deg"]) and math.isfinite(r.metrics["pwm_pp_us"])


def test_bench_run_forwards_the_s4_doublet_to_the_stand_in(tmp_path, fake_sitl_binary,
                                                          monkeypatch):
    """S4's roll doublet, moved to 2 s after take-off, reaches the stand-in ArduCopter as
    SET_ATTITUDE_TARGET at >= 10 Hz of sim time, GUIDED, rates ignored, thrust = hold; the
    log scores the command we sent and times the JSON link."""
    from silbridge.bridge.scenario import SCENARIO_DIR
    from silbridge.tools.benchmark.campaign import make_specs, run_one

    text = (SCENARIO_DIR / "S4.toml").read_text()
    text = text.replace("start_s = 10.0", "start_s = 2.0").replace("repeat = 6", "repeat = 1")
    text = text.replace("start_s = 20.0", "start_s = 60.0").replace("repeat = 5", "repeat = 1")
    path = tmp_path / "S4short.toml"
    path.write_text(text)
    report = tmp_path / "fake_report.json"
    monkeypatch.setenv("FAKE_ARDUCOPTER_REPORT", str(report))
    spec = make_specs([str(path)], 1, 7.0, tmp_path, fc="ardupilot", sitl=fake_sitl_binary,
                      variant="ardupilot",
                      windows=((0.0, 2.0), (2.0, 3.0), (2.0, 7.0), (6.0, 7.0)))[0]
    r = run_one(spec)
    sp = load_scenario(str(path), seed=spec.seed).setpoints[0]
    amp_rad, hold_s = math.radians(sp.amplitude_deg[0]), sp.hold_s[0]
    assert r.problems == [] and not r.summary["crashed"]
    takeoff_s = r.summary["takeoff_physics_s"]
    # Forwarding starts at take-off altitude or, at the latest, with the doublet's first step.
    assert r.summary["setpoints_sent"] > 100 and r.summary["forwarding_from_s"] <= 2.021

    got = json.loads(report.read_text())
    assert got["refused"] == [] and got["timeouts"] == 0 and got["not_guided"] == 0
    rows = np.array(got["set_attitude_target"])
    t_s = rows[:, 0] - takeoff_s                 # flight time at the stand-in's arrival
    assert t_s[0] >= 0.0 and np.diff(t_s).max() <= 0.1          # >= 10 Hz of sim time
    assert (rows[:, 6] == 0b111).all() and (rows[:, 7:9] == 1).all()
    assert np.abs(rows[:, 5] - 0.5).max() <= 0.3                 # climb-rate commands
    roll = np.array([_roll_pitch_yaw(q)[0] for q in rows[:, 1:5]])
    assert roll.max() == pytest.approx(amp_rad, abs=1e-4)
    assert np.abs(roll[t_s < 2.0]).max(initial=0.0) < 1e-6
    at_top = t_s[roll > amp_rad - 1e-4]
    assert at_top.min() == pytest.approx(2.5, abs=0.01)          # the 0.5 s ramp's end
    assert at_top.max() == pytest.approx(2.5 + hold_s, abs=0.06)

    log = read_log(spec.log_path)
    st = log.channels["/fc/status"]
    assert st["att_target_rad"][:, 0].max() == pytest.approx(amp_rad, rel=1e-5)
    assert np.nanmax(st["ap_target_rad"][:, 0]) == pytest.approx(amp_rad, abs=1e-4)  # echo
    tim = log.channels["/timing"]
    assert len(tim) == len(log.channels["/pwm"]) == 7000
    for key in ("latency_ms", "latency_p99_ms", "jitter_ms", "loop_period_ms"):
        assert math.isfinite(r.metrics[key]) and r.metrics[key] >= 0.0, key
    assert r.metrics["loop_period_ms"] > r.metrics["latency_ms"] > 0.0


def test_bench_cli_puts_both_controllers_in_one_table(tmp_path, fake_sitl_binary):
    p = subprocess.run(CLI + ["bench", "--fc", "ours,ardupilot", "--arducopter", fake_sitl_binary,
                              "--scenarios", "S1", "--runs", "1", "--duration", "4",
                              "--jobs", "1", "--warmup", "0", "1", "--transient", "1", "2",
                              "--analysis", "2", "4", "--yaw-window", "2", "4",
                              "--no-report", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    header = next(line for line in p.stdout.splitlines() if line.startswith("| metric"))
    assert header.split(" | ")[1:4] == ["S1 ours", "S1 paper", "S1 ArduCopter |"]
    table = json.loads((tmp_path / "table1.json").read_text())
    assert set(table["scenarios"]) == {"S1", "S1 ArduCopter"} and table["fc"] == ["ours", "ardupilot"]
