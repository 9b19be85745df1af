"""The FC -> bridge fault path: FAULT records beside the PWM reach the fault engine.

The real simulator, segment and FC loop: records pushed on the FC's actuator ring are
collected by the bridge the Python way (collect_pwm) and the C way (the lockstep batch of
`fly --processes 1`, step_lockstep.c); the PWM is still the newest PWM record, every sane
FAULT becomes a switch of sim.faults, and a malformed one is counted and dropped.
"""

from __future__ import annotations

import math
import os

import numpy as np

from silbridge.bridge.bridge_driver import prepare_segment, run_bridge
from silbridge.bridge.bridge_loop import BridgeLoop
from silbridge.bridge.fault_records import fault_summary
from silbridge.fc_sil.autoflight import AutoFlight
from silbridge.fc_sil.fault_inject import fault_record
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment
from silbridge.shm import fault_catalog as cat
from silbridge.shm.records import FAULT_DTYPE, RECORD_DTYPE, Kind, empty
from silbridge.tools.loop.flight import FlightOptions, bridge_config, make_simulator


def _pwm(us: int, seq: int = 0) -> np.ndarray:
    r = empty(Kind.PWM, 1)
    r["pwm_us"][0, :4] = us
    r["channel_count"], r["armed"], r["seq"] = 4, 1, seq
    return r


def _raw_fault(unit: int, ftype: int, instance: int, params=(0.0,) * 9, action: int = 1):
    r = empty(Kind.FAULT, 1)
    r["action"], r["unit"], r["type"], r["instance"] = action, unit, ftype, instance
    r["params"][0] = params
    return r


def _name(tag: str) -> str:
    return f"faultrec-{tag}-{os.getpid()}"


def test_fault_records_are_routed_and_malformed_ones_counted():
    sc, sim = make_simulator(FlightOptions(scenario="S1"))
    gnss, glitch = cat.unit_named("gnss"), cat.unit_named("gnss").type_named("glitch")
    nan = (math.nan,) + (0.0,) * 8
    sent = np.concatenate([r.view(RECORD_DTYPE) for r in (
        _pwm(1300, 0),
        fault_record("gnss", "glitch", 1, {"offset_m": (7.0, -3.0, 0.0)}, True, 0),
        _raw_fault(99, 1, 1),                          # no such unit
        _raw_fault(gnss.code, 99, 1),                  # no such type
        _raw_fault(gnss.code, glitch.code, 1, nan),    # a NaN parameter
        _raw_fault(gnss.code, 1, 7),                   # gnss has no instance 7
        _raw_fault(gnss.code, 1, 1, action=5),         # neither on nor off
        _pwm(1420, 1),
    )])
    with Segment.create(_name("py")) as seg, Segment.attach(_name("py")) as fc_seg:
        loop = BridgeLoop(sim, seg, trace=False)
        assert fault_summary(sim.faults, loop.fault_records) == {}   # a fault-free run: no key
        assert fc_seg.actuators.push_batch(sent) == len(sent)
        assert loop.collect_pwm() == 2                 # the two PWM records
        assert loop.pwm_us == (1420, 1420, 1420, 1420)  # the newest PWM, not the last record
        fr = loop.fault_records
        assert (fr.received, fr.malformed) == (6, 5)
        (f,) = sim.faults.active("gnss")
        assert (f.type, f.instance, f.params["offset_m"]) == ("glitch", 1, (7.0, -3.0, 0.0))
        # the off switch clears it
        fc_seg.actuators.push_batch(fault_record("gnss", "glitch", 1, {}, False, 0)
                                    .view(RECORD_DTYPE))
        assert loop.collect_pwm() == 0 and loop.pwm_us == (1420,) * 4
        assert sim.faults.active("gnss") == []
        # the run summary's counts: one switch each way, every gnss record read (the
        # unreadable unit and type under "?")
        assert fault_summary(sim.faults, fr) == {
            "?": {"on": 0, "off": 0, "fault_records": 2},
            "gnss": {"on": 1, "off": 1, "fault_records": 5}}


class _InjectAt(AutoFlight):
    """AutoFlight that forwards one FAULT record at a sim time, as the MAVLink vehicle does."""

    def __init__(self, core, at_ns: int, rec):
        super().__init__(core)
        self.at_ns, self.rec, self.sent_ns = at_ns, rec, None

    def after_batch(self, loop, recs, pwm, status) -> None:
        super().after_batch(loop, recs, pwm, status)
        if self.sent_ns is None and loop.last_sim_ns >= self.at_ns:
            loop.push_records(self.rec)
            self.sent_ns = loop.last_sim_ns

    def next_due_ns(self) -> float:
        due = super().next_due_ns()
        return min(due, self.at_ns) if self.sent_ns is None else due


def test_fault_record_through_the_c_lockstep_batch():
    opts = FlightOptions(scenario="S1", duration_s=8.0, processes=1)
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    rec = fault_record("motor", "thrust_loss", 3, {"remaining": 0.5}, True, 0)
    with Segment.create(_name("c")) as seg:
        prepare_segment(seg, sim, cfg)
        with Segment.attach(_name("c")) as fc_seg:
            core = FlightCore()
            sup = _InjectAt(core, 6_000_000_000, rec)
            fc = FcLoop(core, fc_seg, supervisor=sup)
            assert fc.batch_poll() is not None       # the C batch path is the one under test
            res = run_bridge(sim, seg, cfg, fc_poll=fc.poll, fc_loop=fc, out=lambda s: None)
    assert sup.sent_ns is not None
    (f,) = sim.faults.active("motor")
    assert (f.type, f.instance, f.params["remaining"]) == ("thrust_loss", 3, 0.5)
    # switched on right after the FC sent it: at the step that collected it
    assert 0 <= f.t_on_ns - sup.sent_ns <= 2 * sim.dt_ns
    assert res.faults == {"motor": {"on": 1, "off": 0, "fault_records": 1}}
    assert FAULT_DTYPE.itemsize == 64
