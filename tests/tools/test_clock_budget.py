"""The clock budget (tools/speed/clock_budget.py): perf's samples sorted into a step's parts."""

import pytest

from silbridge.tools.speed import clock_budget as cb

# `perf script -F pid,tid,time,ip,sym,dso` of seven samples: startup, then the bridge's loop
# (pid 10, thread 10) in JSBSim, in a getter, in Python between batches, another of its
# threads (10/12, hashing), and the FC (pid 11) waiting.
SCRIPT = """\
   10/10 100.000000:
\t    1111 _PyEval_EvalFrameDefault (/usr/lib/libpython3.11.so)
\t    2222 main (/usr/bin/python3.11)

   10/10 100.100000:
\t    3333 JSBSim::FGPropagate::Run (/x/_jsbsim.so)
\t    4444 JSBSim::FGFDMExec::Run (/x/_jsbsim.so)
\t    5555 sb_step_run_items (/x/_step.so)
\t    6666 Kernel_run_batch (/x/_step.so)

   10/10 100.200000:
\t    7777 SGPropertyNode::getDoubleValue (/x/_jsbsim.so)
\t    8888 sb_call0 (inlined)
\t    5555 sb_step_run_items (/x/_step.so)
\t    6666 Kernel_run_batch (/x/_step.so)

   11/11 100.250000:
\t    9999 records_ready (inlined)
\t    aaaa sb_handoff_wait (/x/_shm.so)

   10/10 100.300000:
\t    bbbb _PyEval_EvalFrameDefault (/usr/lib/libpython3.11.so)

   10/12 100.350000:
\t    cccc compress (/x/_step.so)
\t    dddd sb_blake2b_update (/x/_step.so)

   10/10 100.400000:
\t    6666 Kernel_run_batch (/x/_step.so)
"""


def test_samples_parse_with_their_stacks():
    s = cb.parse_samples(SCRIPT)
    assert [(p, tid, t) for p, tid, t, _ in s] == [
        (10, 10, 100.0), (10, 10, 100.1), (10, 10, 100.2), (11, 11, 100.25), (10, 10, 100.3),
        (10, 12, 100.35), (10, 10, 100.4)]
    assert s[1][3][:2] == ["JSBSim::FGPropagate::Run", "JSBSim::FGFDMExec::Run"]


def test_each_sample_goes_to_its_part():
    assert cb.part_of(["JSBSim::FGFDMExec::Run", "Kernel_run_batch"]) == "JSBSim run()"
    assert cb.part_of(["getDoubleValue", "sb_call0", "Kernel_run_batch"]) == \
        "JSBSim getters and setters"
    assert cb.part_of(["compress", "sb_blake2b_update", "Kernel_run_batch"]) == "trace hash"
    assert cb.part_of(["compress", "Blake2b_update", "_PyEval_EvalFrameDefault"]) == \
        "trace hash"
    assert cb.part_of(["sb_handoff_wait", "finish", "Kernel_run_batch"]) == \
        "waiting for the FC's answer"
    assert cb.part_of(["memcpy", "Kernel_run_batch"]) == "batch: rings, words, clock"
    # A getter outside the batch (Python reading JSBSim) is Python's, not the batch's.
    assert cb.part_of(["sb_call0", "_PyEval_EvalFrameDefault"]) == "Python between batches"


def test_the_budget_counts_the_loop_only():
    r = cb.budget(cb.parse_samples(SCRIPT))
    # The loop spans the first to the last sample in the batch: the startup sample is out.
    assert r["bridge_samples"] == 4 and abs(r["loop_s"] - 0.3) < 1e-9
    assert r["bridge"]["JSBSim run()"] == 0.25
    assert r["bridge"]["JSBSim getters and setters"] == 0.25
    assert r["bridge"]["Python between batches"] == 0.25
    assert r["fc_samples"] == 1 and r["fc"]["waiting for the bridge"] == 1.0
    # another thread of the bridge's process is beside its loop: not a part, not the FC
    assert r["beside_loop_samples"] == 1 and r["bridge"]["trace hash"] == 0.0


def test_no_batch_sample_is_a_clear_error():
    with pytest.raises(cb.ClockBudgetError, match="no sample inside the lockstep batch"):
        cb.budget(cb.parse_samples(SCRIPT.split("   10/10 100.100000:")[0]))


def _perf_can_sample() -> bool:
    try:
        cb._perf()
    except cb.ClockBudgetError:
        return False
    return True


@pytest.mark.skipif(not _perf_can_sample(), reason="perf is missing or may not sample here "
                    "(Debian: apt-get install linux-perf; kernel.perf_event_paranoid <= 2)")
def test_a_real_flight_is_mostly_jsbsim():
    r = cb.measure(processes=1, duration_s=10.0)
    assert r["trace_hash"]
    shares = r["bridge"]
    assert abs(sum(shares.values()) - 1.0) < 1e-9
    # JSBSim's run() is the largest part of a one-process step, and the FC runs in it.
    assert max(shares, key=shares.get) == "JSBSim run()"
    assert shares["the FC's step (one process)"] > 0 and "fc" not in r
