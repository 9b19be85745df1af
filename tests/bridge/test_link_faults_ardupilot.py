"""Faults of the link to ArduPilot SITL (JSON physics), driven packet by packet.

The physics is fed servo packets as SITL sends them (no SITL needed): one faulted, one
fault-free, same packets; the replies say what SITL would read.
"""

from __future__ import annotations

import json

from link_fault_helpers import scenario_with

from silbridge.bridge.autopilots.ardupilot import json_protocol as apj
from silbridge.bridge.autopilots.ardupilot.physics import ArduPilotPhysics
from silbridge.bridge.simulator import Simulator
from silbridge.tools.loop.fc_param_events import load_flight_scenario


def _replies(scenario: str, pwm_at, steps: int) -> list[dict]:
    sc = load_flight_scenario(scenario)
    phys = ArduPilotPhysics(lambda: Simulator(sc))
    out = []
    for k in range(steps):
        us = pwm_at(k)
        out.append(json.loads(phys.handle(apj.encode_servo_packet(k + 1, (us,) * 4))))
    return out


def test_a_late_reply_carries_the_state_of_delay_ago_under_todays_timestamp(tmp_path):
    path = scenario_with(tmp_path, {"type": "latency", "instance": 1, "delay_s": 0.005,
                                    "at_s": 0.5})
    ramp = lambda k: 1000 + min(k, 1000)      # noqa: E731  a climb: the state keeps changing
    plain = _replies("S1", ramp, 700)
    late = _replies(path, ramp, 700)
    assert late[:500] == plain[:500]
    for k in range(506, 700):          # from the 6th step of the fault on: 5 steps old
        assert late[k]["timestamp"] == plain[k]["timestamp"]
        for key in ("imu", "position", "velocity", "quaternion"):
            assert late[k][key] == plain[k - 5][key], (k, key)


def test_lost_motor_commands_leave_the_motors_where_they_were(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 2, "probability": 1.0,
                                    "at_s": 0.9})
    full_at_1s = lambda k: 1000 if k < 1000 else 2000     # noqa: E731
    plain = _replies("S1", full_at_1s, 1500)
    lost = _replies(path, full_at_1s, 1500)
    # Full throttle reaches the motors only without the fault: one climbs, one stays put.
    assert plain[-1]["position"][2] < lost[-1]["position"][2] - 0.5
    assert max(abs(a - b) for a, b in zip(lost[-1]["position"], lost[900]["position"])) < 1e-3
