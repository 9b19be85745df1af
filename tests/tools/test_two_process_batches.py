"""Two-process lockstep steps in long C batches: the bridge's look at the FC in its own
process follows the wall clock, not every 20 steps of sim time (bridge_driver.py
LOOK_WALL_NS), which cut a batch every 20 steps and cost ~1 us a step of Python. With a log
the same: the rotor spool takes a batch's rows, so the flight does not fall back to the
per-step path."""

import statistics

import pytest

from silbridge.bridge.bridge_loop import BATCH_MAX_STEPS, BridgeLoop
from silbridge.tools.loop import flight


@pytest.mark.parametrize("logged", [False, True])
def test_two_process_batches_are_long(tmp_path, monkeypatch, logged):
    asked = []
    run_batch = BridgeLoop.run_batch

    def counting(self, n):
        asked.append(n)
        return run_batch(self, n)
    monkeypatch.setattr(BridgeLoop, "run_batch", counting)
    opts = flight.FlightOptions(scenario="S1", duration_s=3.0,
                                log_path=str(tmp_path / "p2.mcap") if logged else None)
    summary = flight.fly_two_processes(opts, out=lambda s: None)
    assert summary["trace_hash"]
    assert asked, "the flight ran no C batch"
    # The first window's checks and the end cut some; the rest run at the batch limit.
    assert statistics.median(asked) == BATCH_MAX_STEPS
    assert sum(asked) >= 2_900      # ~3,000 steps, nearly all in C


def test_two_processes_overlap_the_steps_the_fc_answers_with_nothing():
    """The FC promises its next PWM tick (FC_SYNC_NS): at 400 Hz PWM and 1 kHz physics the
    bridge publishes about 3 steps in 5 without waiting, and the flight is the same."""
    opts = flight.FlightOptions(scenario="S2", duration_s=3.0)
    two = flight.fly_two_processes(opts, out=lambda s: None)
    one = flight.fly_one_process(opts, out=lambda s: None)
    assert two["trace_hash"] == one["trace_hash"]
    assert one["steps_overlapped"] == 0
    assert 0.5 * 3_000 < two["steps_overlapped"] <= 0.6 * 3_000
