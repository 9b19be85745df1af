"""Faults of the SIL link against the lockstep handshake, the FC's failsafe and MAVLink HIL.

A link that loses every sensor record must not stall lockstep: each step still closes
(bridge/link_faults.py), and the FC's sensor failsafe meets the loss. Over MAVLink HIL
(--transport udp) the same fault, drawn from the same seed, hits the same records.
"""

from __future__ import annotations

import os
import sys

from link_fault_helpers import scenario_with

from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "fc_sil"))
from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402


def test_all_sensor_records_lost_for_0_2_s_trips_the_imu_failsafe_not_a_hang(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 1, "probability": 1.0,
                                    "at_s": 15.0, "duration_s": 0.2})
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(8.0)
        if 14.9 < t < 15.0:
            st["armed_before"] = v.armed

    # SB_FS_SENS_TO 0.1 s: a 0.2 s silence is a lost IMU.
    f, res = fly_scripted(script, duration_s=16.0, scenario=path,
                          params={"SB_FS_SENS_TO": 0.1})
    assert st["armed_before"] and not f.v.armed
    assert any("IMU data lost" in m[2] for m in f.v.messages)
    assert res.sim_s == 16.0                         # every step was answered
    assert res.link["sensor_dropped"] >= 200 + 20 + 20   # IMU, baro, mag of 0.2 s


def test_a_dead_link_both_ways_does_not_stall_an_fc_in_its_own_process(tmp_path):
    # Both ways at once would show no PWM loss: our FC steps on IMU samples, so with none
    # arriving it sends nothing. Sensors dead first, then motor outputs.
    path = scenario_with(tmp_path, {"type": "drop", "instance": 1, "probability": 1.0,
                                    "at_s": 6.0, "duration_s": 0.2},
                         {"type": "drop", "instance": 2, "probability": 1.0,
                          "at_s": 6.5, "duration_s": 0.2})
    s = fly_two_processes(FlightOptions(scenario=path, duration_s=7.0, processes=2),
                          out=lambda *_: None)
    assert s["sim_s"] == 7.0 and not s["interrupted"]
    assert s["link"]["pwm_dropped"] == 80            # 400 Hz for 0.2 s
    assert s["link"]["sensor_dropped"] >= 200 + 20 + 20


def test_the_same_fault_hits_the_same_records_over_udp(tmp_path):
    path = scenario_with(tmp_path, {"type": "latency", "instance": 0, "delay_s": 0.005,
                                    "jitter_s": 0.003, "at_s": 2.0, "duration_s": 1.0},
                         {"type": "drop", "instance": 0, "probability": 0.3, "at_s": 2.0,
                          "duration_s": 1.0})
    runs = {t: fly_one_process(FlightOptions(scenario=path, duration_s=4.0, processes=1,
                                             transport=t), out=lambda *_: None)
            for t in ("shm", "udp")}
    shm, udp = runs["shm"], runs["udp"]
    assert udp["link"] == shm["link"]
    assert udp["link"]["sensor_dropped"] > 300 and udp["link"]["pwm_dropped"] > 100
    assert udp["link"]["sensor_delayed"] > 0 and udp["link"]["pwm_delayed"] > 0
    assert udp["sim_s"] == 4.0 and not udp["crashed"]
