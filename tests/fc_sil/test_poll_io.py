"""The C poll (Core.poll_io over the shared-memory segment) against the Python poll."""

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.fc_sil import STATUS_DTYPE
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.runtime import FcLoop
from silbridge.shm import Segment
from silbridge.shm import lockstep as ls
from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE


def _fly(name, use_c: bool, steps=600):
    """Owner publishes simulator steps; the FC polls (C or Python); returns the PWM seen."""
    sim = Simulator(load_scenario("S1"))
    out = []
    with Segment.create(name) as seg, Segment.attach(name) as fc_seg:
        core = FlightCore()
        core.arm()
        loop = FcLoop(core, fc_seg)
        if not use_c:
            loop.close()                    # back to the Python poll
        assert (loop.poll == loop._poll_c) == use_c
        buf = np.zeros(64, RECORD_DTYPE)
        pwm = (1000.0,) * 4
        for _ in range(steps):
            seg.sensors.push_batch(sim.step(pwm))
            assert loop.poll() > 0
            assert seg.word(ls.FC_SIM_NS) == sim.sim_ns      # the step is acknowledged
            n = seg.actuators.pop_into(buf)
            if n:
                rec = buf[:n].view(PWM_DTYPE)
                out.append(rec[["sim_ns", "pwm_us", "armed"]].copy())
                pwm = tuple(float(v) for v in rec["pwm_us"][-1, :4])
        summary = loop.summary()
        assert loop.last_sim_ns == sim.sim_ns
    return np.concatenate(out), summary


def test_c_poll_matches_the_python_poll():
    a, sa = _fly("pollio-c", True)
    b, sb = _fly("pollio-py", False)
    assert len(a) == 240                                    # 400 Hz over 0.6 s
    np.testing.assert_array_equal(a, b)
    for key in ("polls", "records", "pwm_published"):
        assert sa[key] == sb[key] > 0
    assert sa["latency_us"]["p50"] is not None and sa["jitter_us"]["p50"] is not None


def test_attach_io_refuses_the_owner_side_and_a_closed_segment():
    core = FlightCore()
    buf = np.zeros(8, RECORD_DTYPE)
    core._c.bind_batch(buf, np.zeros(8, PWM_DTYPE), np.zeros(8, STATUS_DTYPE))
    rings = [np.zeros(8, np.int64) for _ in range(3)]
    with Segment.create("pollio-own") as seg:
        with pytest.raises(ValueError, match="peer"):
            core._c.attach_io(seg._c_api(), fc_sim_word=ls.FC_SIM_NS, latency_ns=rings[0],
                              period_ns=rings[1], e2e_ns=rings[2], words=np.zeros(8, np.int64))
        with Segment.attach("pollio-own") as fc_seg:
            loop = FcLoop(FlightCore(), fc_seg)
            assert loop.poll == loop._poll_c
        with pytest.raises(RuntimeError, match="closed"):
            loop.poll()
