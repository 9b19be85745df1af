"""The C reply line of the ArduPilot JSON physics against its Python reference.

`_step.json_reply` (bridge/src/step_json.c) is what the hot path sends SITL;
`reply_line` (tests/bridge/json_reply_oracle.py) is the readable reference. Both are fed the same
records of real JSBSim steps (hover, doublets, a climb, an 8 kHz IMU averaged per
step, a 500 Hz IMU that leaves steps without a sample) and must give the same
bytes on x86-64 (CPython formats the numbers in both); elsewhere the values must
agree to the printed digits. A non-finite value gives None (the caller raises),
and records out of contract order raise instead of sending a wrong line.
"""

from __future__ import annotations

import math
import platform

import numpy as np
import pytest

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge._step import json_reply
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from json_reply_oracle import reply_line  # tests/bridge/ is on sys.path (conftest.py)

_EXACT = platform.machine() in ("x86_64", "AMD64")


def _values(line: bytes) -> list:
    import json
    d = json.loads(line)
    return [d["timestamp"], *d["imu"]["gyro"], *d["imu"]["accel_body"], *d["position"],
            *d["attitude"], *d["quaternion"], *d["velocity"]]


def _same(c: bytes, py: bytes) -> None:
    if _EXACT:
        assert c == py
    else:
        assert np.allclose(_values(c), _values(py), rtol=2e-9, atol=1e-12)


@pytest.mark.parametrize("scenario,imu_hz,pwm", [
    ("S1", None, 1500.0), ("S4", None, 1580.0), ("S1", 8000, 1700.0), ("S3", 500, 1450.0)])
def test_c_reply_is_the_reference_line(scenario, imu_hz, pwm):
    sim = Simulator(load_scenario(scenario), imu_hz=imu_hz)
    for k in range(1500):
        # uneven motors: attitude, rates and position all move, Euler angles wrap
        m = (pwm + 40.0 * math.sin(k / 50.0), pwm - 30.0, pwm + 25.0, pwm - 20.0)
        recs = sim.step(m)
        _same(json_reply(recs, sim.sim_ns), reply_line(recs.tobytes(), sim.sim_ns))


def test_physics_sends_the_c_line():
    sc = load_scenario("S1")
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    ref = Simulator(sc)
    for k in range(1, 200):
        got = phys.handle(apj.encode_servo_packet(k, [1600] * 4))
        recs = ref.step((1600.0,) * 4)
        assert got == json_reply(recs, ref.sim_ns)


def test_non_finite_gives_none_and_the_reference_says_why():
    sim = Simulator(load_scenario("S1"))
    recs = sim.step((1000.0,) * 4).copy()
    gt_nav = np.flatnonzero(recs["kind"] == int(Kind.GT_NAV))[0]
    raw = bytearray(recs.tobytes())
    # pos_ned_m[0] is the GT_NAV payload's first double, right after the 24-byte header
    raw[64 * gt_nav + 24:64 * gt_nav + 32] = np.float64(np.nan).tobytes()
    assert json_reply(raw, sim.sim_ns) is None
    with pytest.raises(apj.ArduPilotProtocolError, match="non-finite"):
        reply_line(bytes(raw), sim.sim_ns)


def test_records_out_of_order_or_torn_raise():
    sim = Simulator(load_scenario("S1"))
    recs = sim.step((1000.0,) * 4)
    raw = recs.tobytes()
    with pytest.raises(ValueError, match="contract order"):
        json_reply(raw[:64 * 2], sim.sim_ns)        # IMU, GT_ATT: GT_NAV missing
    with pytest.raises(ValueError, match="64-byte"):
        json_reply(raw[:100], sim.sim_ns)
