"""The one-process lockstep batch (bridge/src/step_batch.c, `fly --processes 1`) against the
per-step path it replaces: same records, same trace hash, same statistics; a stop lands on a
step boundary within one batch; a crash ends the run at the crashing step.

Real JSBSim, real shared memory, the real C core; the per-step path is the reference (run
the same way, without handing run_bridge the FcLoop).
"""

from __future__ import annotations

import os

import pytest

from silbridge.bridge.bridge_driver import BridgeRunConfig, prepare_segment, run_bridge
from silbridge.bridge.bridge_loop import BATCH_MAX_STEPS
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm import Segment
from silbridge.shm import lockstep as ls
from silbridge.tools.loop.flight import make_fc_loop

_NS = 1_000_000_000


class _StopAt:
    """A stop request that turns on once the simulator passed a sim time."""

    name = "SIGINT"

    def __init__(self, sim, at_ns: int):
        self.sim, self.at_ns = sim, at_ns

    @property
    def requested(self) -> bool:
        return self.sim.sim_ns >= self.at_ns


def _fly(scenario: str, duration_s: float, *, batched: bool, overrides=None, stop_at_s=None):
    """One in-process lockstep flight; returns (result, simulator, FC summary, lines, words)."""
    sc = load_scenario(scenario, overrides=overrides or {})
    sim = Simulator(sc)
    cfg = BridgeRunConfig(duration_s=duration_s, settle_s=duration_s / 2)
    name = f"batchtest-{os.getpid()}-{int(batched)}"
    lines: list[str] = []
    stop = _StopAt(sim, int(stop_at_s * _NS)) if stop_at_s is not None else None
    with Segment.create(name) as seg:
        prepare_segment(seg, sim, cfg)
        with Segment.attach(name) as fc_seg:
            fc = make_fc_loop(fc_seg)
            kw = {"stop": stop} if stop is not None else {}
            res = run_bridge(sim, seg, cfg, fc_poll=fc.poll, out=lines.append,
                             fc_loop=fc if batched else None, **kw)
            words = (seg.word(ls.BRIDGE_SIM_NS), seg.word(ls.FC_SIM_NS))
            summary = fc.summary()
            fc.close()
    return res, sim, summary, lines, words


def _same_flight(a, b) -> None:
    ra, sa, fa, _, wa = a
    rb, sb, fb, _, wb = b
    assert ra.trace_hash == rb.trace_hash
    assert (ra.steps, ra.published, ra.pwm_received) == (rb.steps, rb.published, rb.pwm_received)
    assert (ra.attitude_rms_deg, ra.altitude_rms_m) == (rb.attitude_rms_deg, rb.altitude_rms_m)
    assert (fa["polls"], fa["records"], fa["pwm_published"]) == \
        (fb["polls"], fb["records"], fb["pwm_published"])
    assert (sa.crashed, sa.crash_reason) == (sb.crashed, sb.crash_reason)
    assert wa == wb


@pytest.mark.parametrize("scenario, seconds", [("S1", 6.0), ("S2", 10.5)])
def test_batches_give_the_per_step_trace(scenario, seconds):
    """S1 across the arming (the supervisor's due poll), S2 across its disturbance switch at
    10 s: every record, PWM and error sample as the per-step path makes them."""
    batched = _fly(scenario, seconds, batched=True)
    per_step = _fly(scenario, seconds, batched=False)
    assert batched[0].steps_in_c > batched[0].steps * 0.9     # the batch really ran
    assert per_step[0].steps_in_c == 0
    assert batched[0].attitude_rms_deg is not None            # errors sampled (in C)
    _same_flight(batched, per_step)


def test_a_stop_ends_the_run_at_a_step_boundary_within_one_batch():
    """The stop is seen between batches: the run ends on a whole step (the FC answered it),
    at most one batch after the request, with the trace of a run of exactly that length."""
    res, sim, _, lines, words = _fly("S1", 4.0, batched=True, stop_at_s=2.5)
    assert res.interrupted == "SIGINT"
    steps_at_request = int(2.5 * _NS // sim.dt_ns)
    assert steps_at_request <= sim.step_index <= steps_at_request + BATCH_MAX_STEPS
    assert words == (sim.sim_ns, sim.sim_ns)              # published and answered
    assert any(line.startswith("SIGINT: run stopped at t=") for line in lines)
    same_length = _fly("S1", sim.sim_ns / _NS, batched=False)
    assert res.trace_hash == same_length[0].trace_hash


def test_a_crash_inside_a_batch_stops_at_the_crashing_step():
    """Dropped from 6 m with the motors off (the FC arms at 5 s): the hard touchdown is
    flagged by the kernel in the middle of a batch; the run stops at that very step with the
    per-step path's reason, records and hash."""
    high = {"home.initial_agl_m": 6.0}
    batched = _fly("S1", 4.0, batched=True, overrides=high)
    per_step = _fly("S1", 4.0, batched=False, overrides=high)
    res, sim, _, lines, _ = batched
    assert sim.crashed and sim.crash_reason.startswith("hard touchdown")
    assert res.steps < 4000 and res.steps_in_c > 0
    assert f"vehicle crashed at t={sim.sim_ns / _NS:.3f} s; run stopped" in lines
    _same_flight(batched, per_step)
