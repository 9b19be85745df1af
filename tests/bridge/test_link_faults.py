"""Faults of the SIL link (bridge/link_faults.py): what the FC receives and what the motors get.

Real lockstep flights of S1 (JSBSim, segment, C core, FC loop) with [[failure]] entries of
unit "link"; what the FC saw is measured at the FC (its per-cycle sink), the motor command
at the bridge.
"""

from __future__ import annotations

import os

import numpy as np

from link_fault_helpers import fly_watched, scenario_with

from silbridge.bridge.bridge_driver import BridgeRunConfig, prepare_segment
from silbridge.bridge.bridge_loop import BridgeLoop
from silbridge.bridge.simulator import Simulator
from silbridge.fc_sil.autoflight import AutoFlight
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment
from silbridge.shm.records import Kind
from silbridge.tools.loop.fc_param_events import load_flight_scenario
from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes

MS = 1_000_000


def test_latency_delays_what_the_fc_receives_by_the_declared_sim_time(tmp_path):
    path = scenario_with(tmp_path, {"type": "latency", "instance": 1, "delay_s": 0.012,
                                    "at_s": 3.0, "duration_s": 1.0})
    watch, res = fly_watched(path, 5.0)
    imu = watch.arrivals(Kind.IMU)
    late = imu[:, 0] - imu[:, 1]            # arrival step - sample time, sim ns
    # On before the first step that starts at 3 s: samples after 3 s, through 4 s.
    before = imu[:, 1] <= 3000 * MS
    during = (imu[:, 1] > 3000 * MS) & (imu[:, 1] <= 4000 * MS)
    assert (late[before] == 0).all()
    assert (late[during] == 12 * MS).all() and during.sum() == 1000
    # Every sample arrives once, in order, none lost; the FC answered every step.
    assert (np.diff(imu[:, 1]) > 0).all() and len(imu) == 5000
    baro = watch.arrivals(Kind.BARO)
    b_during = (baro[:, 1] > 3000 * MS) & (baro[:, 1] <= 4000 * MS)
    assert (baro[b_during, 0] - baro[b_during, 1] == 12 * MS).all()
    # The clock records are never late: each poll closes its own step.
    steps = [t for t, _ in watch.polls]
    assert steps == list(range(MS, 5001 * MS, MS))
    assert res.link["sensor_delayed"] >= 1000 + 100 + 100 and res.link["sensor_dropped"] == 0
    assert res.link["pwm_delayed"] == res.link["pwm_dropped"] == 0


def test_jitter_keeps_the_order_and_stays_within_delay_plus_jitter(tmp_path):
    path = scenario_with(tmp_path, {"type": "latency", "instance": 1, "delay_s": 0.004,
                                    "jitter_s": 0.006, "at_s": 3.0, "duration_s": 1.0})
    watch, _ = fly_watched(path, 4.5)
    imu = watch.arrivals(Kind.IMU)
    late = imu[:, 0] - imu[:, 1]
    during = (imu[:, 1] > 3000 * MS) & (imu[:, 1] <= 4000 * MS)
    assert (np.diff(imu[:, 1]) > 0).all()         # FIFO: a record never overtakes another
    assert late[during].min() >= 4 * MS and late[during].max() <= 10 * MS
    assert len(set(late[during].tolist())) > 3     # the jitter varies the delay


def _drop_run(path: str) -> dict:
    return fly_two_processes(FlightOptions(scenario=path, duration_s=4.0, processes=2),
                             out=lambda *_: None)


def test_drop_loses_about_the_declared_fraction_and_the_same_records_each_run(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 1, "probability": 0.3,
                                    "at_s": 2.0, "duration_s": 1.0})
    a, b = _drop_run(path), _drop_run(path)
    # One second of IMU, baro, mag, GNSS and battery records crossed the link: ~1230.
    sent = 1000 + 100 + 100 + 10 + 10
    n = a["link"]["sensor_dropped"]
    sigma = (sent * 0.3 * 0.7) ** 0.5
    assert abs(n - 0.3 * sent) < 4 * sigma, n
    assert a["link"] == b["link"] and a["trace_hash"] == b["trace_hash"]
    assert a["link"]["sensor_delayed"] == 0 and not a["crashed"]


def test_dropped_records_never_reach_the_fc(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 1, "probability": 0.3,
                                    "at_s": 2.0, "duration_s": 1.0})
    watch, res = fly_watched(path, 3.5)
    imu = watch.arrivals(Kind.IMU)
    during = (imu[:, 1] > 2000 * MS) & (imu[:, 1] <= 3000 * MS)
    assert (imu[:, 0] == imu[:, 1]).all()         # what arrives arrives on time
    assert 3500 - len(imu) == 1000 - during.sum()
    assert 1000 - during.sum() <= res.link["sensor_dropped"]


def test_pwm_drop_holds_the_last_outputs(tmp_path):
    path = scenario_with(tmp_path, {"type": "drop", "instance": 2, "probability": 1.0,
                                    "at_s": 6.0, "duration_s": 0.5})
    sim = Simulator(load_flight_scenario(path))
    name = f"linkpwm-{os.getpid()}"
    rows = []
    with Segment.create(name) as seg:
        prepare_segment(seg, sim, BridgeRunConfig(duration_s=7.0))
        with Segment.attach(name) as fc_seg:
            core = FlightCore()
            fc = FcLoop(core, fc_seg, supervisor=AutoFlight(core))
            loop = BridgeLoop(sim, seg)
            for _ in range(7000):
                loop.publish_step()
                fc.poll()
                loop.collect_pwm()
                rows.append((sim.sim_ns, loop.pwm_us, loop.stats.pwm_received))
    t = np.array([r[0] for r in rows])
    us = np.array([r[1] for r in rows])
    sent = np.array([r[2] for r in rows])
    during = (t > 6000 * MS) & (t <= 6500 * MS)
    held = us[during]
    assert (held == us[np.flatnonzero(during)[0] - 1]).all()    # the command before the fault
    assert sent[during][-1] - sent[during][0] >= 199               # the FC kept sending
    after = us[(t > 6500 * MS) & (t <= 6600 * MS)]
    assert (after != held[0]).any()                                # new commands arrive again
    assert loop.link.counts()["pwm_dropped"] == 200                 # 400 Hz for 0.5 s


def test_a_null_fault_changes_nothing_in_either_placement(tmp_path):
    # Delay 0 and drop 0, on for most of the run: every step goes the per-step way and
    # through the link's filters, and the trace is the fault-free one, bit for bit.
    path = scenario_with(tmp_path, {"type": "latency", "instance": 0, "delay_s": 0.0,
                                    "at_s": 1.0, "duration_s": 2.0},
                         {"type": "drop", "instance": 0, "probability": 0.0, "at_s": 1.5})
    plain = fly_one_process(FlightOptions(scenario="S1", duration_s=4.0, processes=1),
                            out=lambda *_: None)
    for fly in (fly_one_process, fly_two_processes):
        s = fly(FlightOptions(scenario=path, duration_s=4.0, processes=2), out=lambda *_: None)
        assert s["trace_hash"] == plain["trace_hash"], fly.__name__
