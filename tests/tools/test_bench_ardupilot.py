"""`silbridge bench --fc ardupilot` and `silbridge bridge --fc ardupilot` without and with SITL.

Always run: the skip path without a binary (exit 0, says how to get one), the
`bridge --fc ardupilot` command against a fake SITL, the bridge-side log of an
ArduCopter flight through the real integrity check and metrics, the SITL
defaults, the MAVLink driver (GUIDED, arm, take-off, commanded attitude)
against a fake ArduCopter MAVLink port, and whole bench runs with a stand-in
`arducopter` executable (fake_arducopter.py: same command line, ports and
protocols, a plain altitude hold). With SILBRIDGE_ARDUCOPTER pointing at
an arducopter binary, an end-to-end run arms, takes off and hovers for 30 s of
sim time on our physics.
"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge import ardupilot_json as apj
from silbridge.bridge.ardupilot_physics import ArduPilotPhysics
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.tools.ardupilot_log import SOURCE_ATTITUDE_TARGET, ArduPilotLogSink, AttitudeTarget
from silbridge.tools.integrity import check_log
from silbridge.tools.mcap_log import read_log
from silbridge.tools.metrics import Windows, compute_metrics
from silbridge.tools.sitl_ardupilot import (
    COPTER_MODE_GUIDED,
    MavlinkDriver,
    find_arducopter,
    sitl_defaults,
    write_defaults,
)

CLI = [sys.executable, "-m", "silbridge.tools"]


def _env_without_sitl(tmp_path) -> dict:
    env = dict(os.environ)
    env.pop("SILBRIDGE_ARDUCOPTER", None)
    env["PATH"] = f"{Path(sys.executable).parent}:/usr/bin:/bin"
    return env


def test_bench_without_binary_skips_and_says_how_to_get_one(tmp_path):
    if find_arducopter() is not None:
        pytest.skip("an arducopter binary is installed here: the skip path cannot be shown")
    p = subprocess.run(CLI + ["bench", "--fc", "ardupilot", "--scenarios", "S1", "--runs", "1",
                              "--duration", "1", "--out", str(tmp_path), "--json"],
                       capture_output=True, text=True, env=_env_without_sitl(tmp_path), timeout=60)
    assert p.returncode == 0, p.stderr
    assert "Traceback" not in p.stderr
    assert "SILBRIDGE_ARDUCOPTER" in p.stderr and "waf" in p.stderr
    out = json.loads(p.stdout)
    assert out["skipped"] is True and out["fc"] == "ardupilot"


def test_bench_with_a_missing_binary_is_a_user_error(tmp_path):
    p = subprocess.run(CLI + ["bench", "--fc", "ardupilot", "--sitl", str(tmp_path / "nope"),
                              "--scenarios", "S1", "--runs", "1", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2
    assert "Traceback" not in p.stderr and "./waf copter" in p.stderr


def test_bench_refuses_an_unknown_fc(tmp_path):
    p = subprocess.run(CLI + ["bench", "--fc", "px4", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "--fc wants" in p.stderr


def test_bridge_command_serves_a_fake_sitl():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    proc = subprocess.Popen(CLI + ["bridge", "--fc", "ardupilot", "--sitl-address",
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


def test_bridge_side_log_passes_integrity_and_gives_metrics(tmp_path):
    """Physics + log sink as a bench run uses them, fed by servo packets: log from take-off."""
    sc = load_scenario("S1")
    target = AttitudeTarget()
    path = tmp_path / "ap.mcap"
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    meta = {"config": {"imu_hz": phys.sim.imu_hz, "pwm_hz": 1000.0, "physics_hz": 1000.0,
                       "baro_hz": sc.baro_hz, "mag_hz": sc.mag_hz, "gnss_hz": sc.gnss_hz,
                       "duration_s": 2.0, "seed": sc.seed},
            "params": {"MOT_PWM_MIN": 1000, "MOT_PWM_MAX": 2000}}
    sink = ArduPilotLogSink(path, metadata=meta, target=target, duration_s=2.0)
    phys.sink = sink
    frame = 0
    while not sink.done:
        frame += 1
        if frame == 500:
            sink.start_at(phys.sim.sim_ns)       # "take-off accepted" at 0.5 s
        if frame == 800:
            target.set(0.02, -0.01, 0.0, SOURCE_ATTITUDE_TARGET)
        phys.handle(apj.encode_servo_packet(frame, [1400, 1400, 1400, 1400]))
    sink.close()
    log = read_log(path)
    assert check_log(log) == []
    st = log.channels["/fc/status"]
    assert st["sim_ns"][0] == 0 and len(st) == 2000
    assert "/setpoint" not in log.channels
    assert log.channels["/pwm"]["pwm_us"][:, :4].min() == 1400
    m = compute_metrics(log, Windows(warmup=(0, 0.5), transient=(0.5, 1.0), analysis=(1.0, 2.0),
                                     yaw=(1.5, 2.0)))
    # On the ground the attitude is level: the error is the commanded 2.2 deg.
    assert m["att_rms_deg"] == pytest.approx(math.degrees(math.hypot(0.02, 0.01)), abs=0.3)
    assert m["pwm_pp_us"] == 0.0 and m["sat_pct"] == 0.0


def test_sitl_defaults_match_our_quad_x(tmp_path):
    sim = Simulator(load_scenario("S1"))
    d = sitl_defaults(sim, 1000.0, {"ATC_RAT_RLL_P": 0.12})
    assert d["FRAME_CLASS"] == 1 and d["FRAME_TYPE"] == 1 and d["SIM_RATE_HZ"] == 1000
    assert (d["MOT_PWM_MIN"], d["MOT_PWM_MAX"]) == (1000, 2000)
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
                next_beat = time.monotonic() + 0.05
            try:
                data = self.conn.recv(4096)
            except socket.timeout:
                continue
            if not data:
                return
            for m in codec.parse_buffer(data) or []:
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
        while target.get()[1] != SOURCE_ATTITUDE_TARGET and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        drv.stop()
        fake.close()
    assert drv.error is None
    assert fake.mode == COPTER_MODE_GUIDED and fake.armed and fake.takeoff_alt == 10.0
    assert fake.intervals[mav.MAVLINK_MSG_ID_ATTITUDE_TARGET] == pytest.approx(20000)
    (roll, pitch, _), source = target.get()
    assert source == SOURCE_ATTITUDE_TARGET and roll == pytest.approx(0.1, abs=1e-6)


@pytest.mark.skipif(not os.environ.get("SILBRIDGE_ARDUCOPTER"),
                    reason="set SILBRIDGE_ARDUCOPTER to an arducopter SITL binary to fly it "
                           "end to end (none on this machine; see README 'ArduCopter SITL')")
def test_arducopter_arms_takes_off_and_hovers_30_s(tmp_path):
    from silbridge.tools.campaign import make_specs, run_one

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
    assert abs(alt_m.mean() - 10.0) < 1.0        # GUIDED holds the take-off altitude
    assert math.isfinite(r.metrics["att_rms_deg"]) and r.metrics["att_rms_deg"] < 5.0


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
    from silbridge.tools.campaign import make_specs, run_one

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


def test_bench_cli_puts_both_controllers_in_one_table(tmp_path, fake_sitl_binary):
    p = subprocess.run(CLI + ["bench", "--fc", "ours,ardupilot", "--sitl", fake_sitl_binary,
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
