"""Two-process lockstep on a machine where the FC sleeps between steps.

- The bridge's batch wakes a sleeping FC only before it waits for its answer: at 400 Hz PWM
  and 1 kHz physics the FC is woken about 2 steps in 5, not on every step (each wake is a
  system call, and across two CPUs an interrupt to the FC's).
- The STACK way of waiting (shm/include/sb_handoff_choice.h) holds both processes on the
  bridge's CPU and flies the same flight.
The ways of waiting are forced (SILBRIDGE_HANDOFF) so that the test does not depend on what
the machine's load makes the bridge choose; no timing is asserted.
"""

import pytest

from silbridge.tools.loop import flight

DURATION_S = 3.0
STEPS = 3_000


def _fly(monkeypatch, arm):
    monkeypatch.setenv("SILBRIDGE_HANDOFF", arm)
    seen = {}
    run_bridge = flight.run_bridge

    def watching(sim, seg, cfg, **kw):
        try:
            return run_bridge(sim, seg, cfg, **kw)
        finally:
            seen["info"], seen["handoff"] = seg.info, seg.handoff_stats()
    monkeypatch.setattr(flight, "run_bridge", watching)
    opts = flight.FlightOptions(scenario="S1", duration_s=DURATION_S)
    return flight.fly_two_processes(opts, out=lambda s: None), seen


def test_a_sleeping_fc_is_woken_only_for_the_steps_the_bridge_waits_for(monkeypatch):
    summary, seen = _fly(monkeypatch, "block")
    bridge_wakes_fc = seen["info"]["bell_wakes"][0]
    waits = seen["handoff"]["waits"]
    assert 0.5 * STEPS < summary["steps_overlapped"] <= 0.6 * STEPS
    # One wake at most per wait (the FC may still be awake from the step before), none for
    # the steps published without a wait.
    assert 0 < bridge_wakes_fc <= waits + 10
    assert bridge_wakes_fc < 0.5 * STEPS


def test_stack_holds_both_processes_on_one_cpu_and_flies_the_same_flight(monkeypatch):
    one = flight.fly_one_process(flight.FlightOptions(scenario="S1", duration_s=DURATION_S),
                                 out=lambda s: None)
    summary, seen = _fly(monkeypatch, "stack")
    assert summary["trace_hash"] == one["trace_hash"]
    assert seen["handoff"]["arm"] == "stack" and seen["handoff"]["held_cpu"] >= 0
    # One CPU: neither side spins (the other could not run meanwhile).
    assert seen["handoff"]["spun"] == 0


@pytest.mark.parametrize("arm", ["spin", "block"])
def test_the_ways_across_two_cpus_hold_none(monkeypatch, arm):
    _, seen = _fly(monkeypatch, arm)
    assert seen["handoff"]["held_cpu"] == -1
