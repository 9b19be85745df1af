"""The FC's promise (FC_SYNC_NS, shm/lockstep.py): with each answer its C poll names the next
step whose answer the bridge must wait for: its next PWM tick, or Python's due poll if that
comes first, and no promise at all (0) after a poll its Python follows. The bridge publishes
the steps before it without waiting, so a promise too late would hand the motors a PWM a
step late; one too early only costs a wait."""

import math

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment
from silbridge.shm import lockstep as ls
from silbridge.shm.records import PWM_DTYPE, RECORD_DTYPE

_PWM_PERIOD_NS = 2_500_000      # SB_PWM_HZ 400


def _next_tick(sim_ns: int) -> int:
    return (sim_ns // _PWM_PERIOD_NS + 1) * _PWM_PERIOD_NS


def _steps(name, until, steps=400):
    """Owner publishes simulator steps one at a time; after each FC poll: (the step's sim
    time, whether it carried a hand-on kind, PWM ticks emitted, the promise)."""
    sim = Simulator(load_scenario("S1"))
    rows = []
    with Segment.create(name) as seg, Segment.attach(name) as fc_seg:
        core = FlightCore()
        core.arm()
        loop = FcLoop(core, fc_seg)
        assert loop.polls_in_c
        loop.promise_until(until)
        buf = np.zeros(64, RECORD_DTYPE)
        pwm = (1000.0,) * 4
        for _ in range(steps):
            recs = sim.step(pwm)
            seg.sensors.push_batch(recs)
            assert loop.poll() > 0
            hand_on = any((ls.HAND_ON_KINDS >> int(k)) & 1 for k in recs["kind"])
            n = seg.actuators.pop_into(buf)
            ticks = [int(t) for t in buf[:n].view(PWM_DTYPE)["sim_ns"]]
            if n:
                pwm = tuple(float(v) for v in buf[:n].view(PWM_DTYPE)["pwm_us"][-1, :4])
            rows.append((sim.sim_ns, hand_on, ticks, seg.word(ls.FC_SYNC_NS)))
        loop.close()
    return rows


def test_the_promise_is_the_next_pwm_tick_and_none_after_a_hand_on_poll():
    rows = _steps("sync-tick", math.inf)
    assert any(h for _, h, _, _ in rows), "no GNSS epoch in 0.4 s: the test saw no hand-on"
    for sim_ns, hand_on, _, promise in rows:
        assert promise == (0 if hand_on else _next_tick(sim_ns)), sim_ns
    # The promise holds: every PWM came at or after the step the answer before it named.
    before = 0
    for sim_ns, _, ticks, promise in rows:
        assert all(before <= t <= sim_ns for t in ticks), (sim_ns, ticks, before)
        before = promise
    assert sum(len(t) for _, _, t, _ in rows) == 160          # 400 Hz over 0.4 s


def test_python_s_due_poll_comes_first_and_zero_promises_nothing():
    due = 101_000_000      # the first step at or after it is one Python follows
    for sim_ns, hand_on, _, promise in _steps("sync-due", due, steps=150):
        if not hand_on:
            assert promise == min(due, _next_tick(sim_ns))
    for _, _, _, promise in _steps("sync-zero", 0, steps=50):
        assert promise == 0
