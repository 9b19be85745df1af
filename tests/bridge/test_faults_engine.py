"""The fault engine (bridge/faults/engine.py): runtime injection takes effect at the next
step and clears with on=False, bad faults are refused by name, a unit nobody applies is an
error, the FC's units are reported, and a step batch gives the per-step records with
failures declared (the switches end a batch, as disturbance switches do).
"""

from __future__ import annotations

import numpy as np
import pytest

from bridge_test_helpers import of_kind
from silbridge.bridge.faults.engine import FaultEngine, FaultError
from silbridge.bridge.scenario import Section, load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind
from test_step_batch import _fly, _same_flight


def _gyro_rows(sim, steps, inject_at=None, clear_at=None):
    rows = []
    for k in range(1, steps + 1):
        if k == inject_at:
            sim.faults.inject("gyro", "bias", 1, {"bias": (0.1, 0.0, -0.2)}, True, sim.sim_ns)
        if k == clear_at:
            sim.faults.inject("gyro", "bias", 1, {}, False, sim.sim_ns)
        rows.append(of_kind(sim.step((sim.hover_pwm_us,) * 4), Kind.IMU)["gyro_frd_rad_s"][0])
    return np.array(rows, dtype=float)


def test_inject_acts_from_the_next_step_and_clears():
    sim = Simulator(load_scenario("S1"))
    a = _gyro_rows(sim, 300, inject_at=101, clear_at=201)
    b = _gyro_rows(Simulator(load_scenario("S1")), 300)
    assert (a[:100] == b[:100]).all() and (a[200:] == b[200:]).all()
    np.testing.assert_allclose(a[100:200] - b[100:200], np.tile([0.1, 0.0, -0.2], (100, 1)),
                               atol=1e-6)
    events = sim.drain_events()
    assert events == [(100_000_000, "inject on: gyro.bias[1] bias=[0.1, 0, -0.2]"),
                      (200_000_000, "inject off: gyro.bias[1] bias=[0.1, 0, -0.2]")]
    assert sim.faults.active("gyro") == []


def test_active_lists_the_fault_with_its_parameters_and_time():
    sim = Simulator(load_scenario("S1"))
    sim.faults.inject("motor", "desync", 3, {"rate_hz": 1.0}, True, 5_000_000)
    (f,) = sim.faults.active("motor")
    assert (f.unit, f.type, f.instance, f.t_on_ns) == ("motor", "desync", 3, 5_000_000)
    assert f.params == {"rate_hz": 1.0, "dropout_s": 0.05}    # the catalog's default filled in


@pytest.mark.parametrize("args, words", [
    (("gnss", "wobble", 1, {}), ["gnss fault type 'wobble'", "glitch"]),
    (("compass", "off", 1, {}), ["unit 'compass'", "mag"]),
    (("motor", "thrust_loss", 5, {}), ["no instance 5", "0, 1, 2, 3, 4"]),
    (("baro", "drift", 1, {"rate": 1.0}), ["parameter 'rate'", "rate_m_s"]),
])
def test_inject_refuses_a_wrong_fault_by_name(args, words):
    sim = Simulator(load_scenario("S1"))
    with pytest.raises(FaultError) as err:
        sim.faults.inject(*args, True, 0)
    assert all(w in str(err.value) for w in words)
    assert sim.faults.all_active() == []


def _entry(**kw):
    return Section({"instance": 1, "at_s": 0.0, "duration_s": None, **kw})


def test_a_unit_nobody_applies_is_an_error_at_the_first_step():
    events = []
    engine = FaultEngine([_entry(unit="link", type="drop", probability=0.5)], 1_000_000, 5.0,
                         lambda ns, text: events.append(text))
    assert engine.next_step == 1
    with pytest.raises(FaultError, match="failure\\[0\\]: no part of this run applies link"):
        engine.switch(1)


def test_fc_side_units_are_reported_without_an_applier():
    events = []
    engine = FaultEngine([_entry(unit="rc", type="lost", at_s=0.002, duration_s=0.001)],
                         1_000_000, 5.0, lambda ns, text: events.append((ns, text)))
    for k in range(1, 6):
        if k == engine.next_step:
            engine.switch(k)
        if k == 3:
            assert [f.type for f in engine.active("rc")] == ["lost"]
    assert engine.active("rc") == [] and engine.next_step == -1
    assert events == [(2_000_000, "failure[0] on: rc.lost[1]"),
                      (3_000_000, "failure[0] off: rc.lost[1]")]


FAILURES = [
    {"unit": "gyro", "type": "bias", "at_s": 2.0, "duration_s": 1.0, "bias": [0.02, 0.0, 0.0]},
    {"unit": "gnss", "type": "glitch", "at_s": 2.5, "duration_s": 1.0},
    {"unit": "baro", "type": "drift", "at_s": 2.2, "rate_m_s": 0.5},
    {"unit": "motor", "type": "desync", "instance": 4, "at_s": 3.0, "rate_hz": 4.0,
     "dropout_s": 0.02},
]


def test_batches_give_the_per_step_trace_with_failures():
    """S1 in closed loop with the failures above: every record and PWM as the per-step path
    makes them, and not the fault-free flight's."""
    over = {"failure": FAILURES}
    batched = _fly("S1", 4.5, batched=True, overrides=over)
    per_step = _fly("S1", 4.5, batched=False, overrides=over)
    assert batched[0].steps_in_c > batched[0].steps * 0.5
    _same_flight(batched, per_step)
    assert batched[0].trace_hash != _fly("S1", 4.5, batched=True)[0].trace_hash


def test_a_fault_its_applier_refuses_is_not_left_on():
    sim = Simulator(load_scenario("S1"))       # [vibration] off
    with pytest.raises(FaultError, match="vibrating world"):
        sim.faults.inject("motor", "damaged_prop", 2, {}, True, 0)
    assert sim.faults.active("motor") == []
    sim.faults.inject("motor", "damaged_prop", 2, {"imbalance_scale": 1.0}, True, 0)
    assert sim.truth()["thrust_scale"] == (1.0, 0.85, 1.0, 1.0)


def test_an_earlier_entrys_end_does_not_clear_a_later_one():
    events = []
    engine = FaultEngine([_entry(unit="gcs", type="lost", at_s=0.001, duration_s=0.003),
                          _entry(unit="gcs", type="lost", at_s=0.002, duration_s=0.005)],
                         1_000_000, 5.0, lambda ns, text: events.append(text))
    for k in range(1, 10):
        if k == engine.next_step:
            engine.switch(k)
        if k == 5:      # entry 0 ended at 4 ms, entry 1 runs to 7 ms
            assert len(engine.active("gcs")) == 1
    assert engine.active("gcs") == []
    assert events == ["failure[0] on: gcs.lost[1]", "failure[1] on: gcs.lost[1]",
                      "failure[1] off: gcs.lost[1]"]
