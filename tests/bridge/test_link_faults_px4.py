"""Faults of the link to PX4 (MAVLink HIL), driven reply by reply (no PX4 needed).

Px4Physics is fed HIL_ACTUATOR_CONTROLS as PX4 sends them, one per 4 ms PX4 step: one
faulted, one fault-free, same replies; the HIL_SENSOR frames say what PX4 would read.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from link_fault_helpers import scenario_with

from silbridge.bridge.autopilots.px4.physics import Px4Physics
from silbridge.bridge.simulator import Simulator
from silbridge.mavlink.hil.hil_channel import make_codec
from silbridge.tools.loop.fc_param_events import load_flight_scenario

ARMED = 128


def _fly(scenario: str, throttle_at, steps: int):
    """PX4 steps under throttle_at(step) on every motor: (HIL_SENSOR messages, last z)."""
    sc = load_flight_scenario(scenario)
    phys = Px4Physics(lambda: Simulator(sc), make_codec(1, 51))
    parser = make_codec(1, 51)
    sensors = []
    for j in range(steps):
        c = throttle_at(j)
        phys.on_controls(mav.MAVLink_hil_actuator_controls_message(
            phys.last_sent_us, [c] * 4 + [0.0] * 12, ARMED, 1))
        out: list = []
        phys.step(out)
        for frame in out:
            for m in parser.parse_buffer(frame) or []:
                if m.get_type() == "HIL_SENSOR":
                    sensors.append(m)
    return sensors, phys.sim.truth()["pos_ned_m"][2]


def test_late_sensors_reach_px4_one_px4_step_late(tmp_path):
    path = scenario_with(tmp_path, {"type": "latency", "instance": 1, "delay_s": 0.004,
                                    "at_s": 0.4})
    ramp = lambda j: min(1.0, j / 150)      # noqa: E731  a climb: the IMU keeps changing
    plain, _ = _fly("S1", ramp, 200)
    late, _ = _fly(path, ramp, 200)
    acc = lambda m: (m.xacc, m.yacc, m.zacc, m.xgyro, m.ygyro, m.zgyro)  # noqa: E731
    assert [acc(m) for m in late[:100]] == [acc(m) for m in plain[:100]]
    for j in range(102, 200):        # 4 ms = one PX4 step: the samples of the step before
        assert late[j].time_usec == plain[j].time_usec
        assert acc(late[j]) == acc(plain[j - 1]), j


def test_lost_px4_outputs_leave_the_motors_where_they_were(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 2, "probability": 1.0,
                                    "at_s": 0.4})
    full_at_half_s = lambda j: 0.0 if j < 125 else 1.0     # noqa: E731
    _, z_plain = _fly("S1", full_at_half_s, 375)
    _, z_lost = _fly(path, full_at_half_s, 375)
    assert z_plain < z_lost - 0.5            # NED: the fault-free one climbed
