"""The lockstep hand-off (shm/include/sb_handoff.h) between two real processes.

- `fly --processes 2` (the FC's waits and C polls served in C, shm/src/serve.c) flies
  exactly what `--processes 1` flies: the same trace hash, and the same FC estimate step by
  step (S2: the FC sets the compass declination at the first GNSS fix, a poll that must reach
  Python in both modes).
- The FC follows the way of waiting the bridge chose (the header's handoff_arm): forced to
  block, neither side spins; every step is answered whatever the way.
- The bridge's batches of steps in C wait for an FC that stalls (SIGSTOP) and fly on
  unchanged; a killed FC stops a lockstep bridge with a message (PeerWatch).
- The C side's lockstep word numbers agree with shm/lockstep.py, and each step word sits on
  its ring's head line (one line per hand-off besides the records).
No timing is asserted: the ways of waiting differ in speed, not in what crosses.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from silbridge.shm import Segment, _ring
from silbridge.shm import lockstep as ls
from silbridge.shm.records import FLAG_STEP_END, RECORD_DTYPE, Kind
from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes
from silbridge.tools.logs.log_reader import read_log

STEPS = 3000

# The FC's side: serve_polls with a Python poll that answers each step with one PWM record.
_PEER = """
import json, sys
import numpy as np
from silbridge.shm import Segment, lockstep as ls
from silbridge.shm.records import RECORD_DTYPE, Kind
from silbridge.shm.segment import serve_polls
seg = Segment.attach(sys.argv[1], timeout_s=10)
buf = np.zeros(64, dtype=RECORD_DTYPE)
pwm = np.zeros(1, dtype=RECORD_DTYPE)
pwm["kind"] = Kind.PWM
def poll():
    n = seg.sensors.pop_into(buf)
    if n:
        sim_ns = int(buf["sim_ns"][n - 1])
        pwm["sim_ns"] = sim_ns
        seg.actuators.push_batch(pwm)
        seg.set_word(ls.FC_SIM_NS, sim_ns)
    return n
cap = seg.c_capsule()
polls = 0
while not seg.word(ls.STOP):
    polls += serve_polls(cap, poll, float("inf"), 1 << 30, 0.5, 0, buf)[0]
import os
print(json.dumps({"polls": polls, "stats": seg.handoff_stats(),
                  "cpus_held": sorted(os.sched_getaffinity(0))}), flush=True)
seg.close()
"""


def _pair(name: str, arm: str | None) -> tuple[dict, dict, list]:
    env = dict(os.environ)
    env.pop("SILBRIDGE_HANDOFF", None)
    if arm is not None:
        env["SILBRIDGE_HANDOFF"] = arm
    # The owner's choice reads the variable when the segment is made: in a child, like the FC.
    owner = """
import json, os, sys
import numpy as np
from silbridge.shm import Segment, lockstep as ls
from silbridge.shm.records import FLAG_STEP_END, RECORD_DTYPE, Kind
steps = int(sys.argv[2])
cpus_before = sorted(os.sched_getaffinity(0))
with Segment.create(sys.argv[1]) as seg:
    seg.set_word(ls.RUN_MODE, ls.MODE_LOCKSTEP)
    peer = __import__("subprocess").Popen([sys.executable, "-c", sys.argv[3], sys.argv[1]],
                                          stdout=__import__("subprocess").PIPE, text=True)
    rec = np.zeros(1, dtype=RECORD_DTYPE)
    rec["kind"], rec["flags"] = Kind.IMU, FLAG_STEP_END
    out = np.zeros(8, dtype=RECORD_DTYPE)
    answers = []
    for k in range(1, steps + 1):
        rec["sim_ns"] = k
        seg.sensors.push_batch(rec)
        seg.set_word(ls.BRIDGE_SIM_NS, k)
        while not seg.wait_word(ls.FC_SIM_NS, k, 0.02):
            assert peer.poll() is None, "the FC died"
        n = seg.actuators.pop_into(out)
        answers += [int(s) for s in out["sim_ns"][:n]]
    seg.set_word(ls.STOP, ls.STOP_DONE)
    fc = json.loads(peer.communicate(timeout=30)[0])
    stats = seg.handoff_stats()     # after the FC's last wait: its trouble all published
    stats["cpus_held"] = sorted(os.sched_getaffinity(0))
stats["cpus_before"], stats["cpus_after"] = cpus_before, sorted(os.sched_getaffinity(0))
print(json.dumps({"owner": stats, "fc": fc, "answers": answers}))
"""
    done = subprocess.run([sys.executable, "-c", owner, name, str(STEPS), _PEER], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    r = json.loads(done.stdout.strip().splitlines()[-1])
    return r["owner"], r["fc"], r["answers"]


@pytest.mark.parametrize("arm", [None, "spin", "brief", "block", "stack"])
def test_every_step_is_answered_whatever_the_way_of_waiting(name, arm):
    owner, fc, answers = _pair(name, arm)
    assert answers == list(range(1, STEPS + 1))
    assert owner["waits"] - owner["timeouts"] == STEPS and fc["polls"] == STEPS
    assert owner["arm"] == fc["stats"]["arm"] == (arm or owner["arm"])
    # What the FC's spins lost is what the bridge's choice counted.
    assert owner["peer_trouble"] == fc["stats"]["ran_out"] + fc["stats"]["preempted"]


def test_the_fc_follows_the_bridges_choice_to_block(name):
    owner, fc, _ = _pair(name, "block")
    assert owner["forced"] and owner["probes"] == 0
    for side in (owner, fc["stats"]):
        assert side["spun"] == side["ran_out"] == side["preempted"] == 0, side
        assert side["blocked"] + side["ready"] == side["waits"], side


def test_stack_holds_both_sides_on_the_bridges_cpu_and_gives_the_cpus_back(name):
    owner, fc, answers = _pair(name, "stack")
    assert answers == list(range(1, STEPS + 1))
    cpu = owner["held_cpu"]
    assert cpu >= 0 and fc["stats"]["held_cpu"] == cpu
    assert owner["cpus_held"] == fc["cpus_held"] == [cpu]
    # Closing the segment gave the bridge's thread back every CPU it had.
    assert owner["cpus_after"] == owner["cpus_before"]
    for side in (owner, fc["stats"]):     # one CPU: spinning would only delay the other
        assert side["spun"] == side["ran_out"] == side["preempted"] == 0, side


def test_the_other_ways_hold_no_cpu(name):
    owner, fc, _ = _pair(name, "spin")
    assert owner["held_cpu"] == fc["stats"]["held_cpu"] == -1
    assert owner["cpus_held"] == owner["cpus_before"]


def test_the_fc_blocks_at_once_in_brief(name):
    # BRIEF: only the bridge spins (the FC's answer is quick, the bridge's step is not).
    _, fc, _ = _pair(name, "brief")
    st = fc["stats"]
    assert st["spun"] == st["ran_out"] == st["preempted"] == 0, st


def test_lockstep_word_numbers_and_lines_agree_with_lockstep_py():
    lay, seg = _ring.lockstep_layout(), _ring.layout()
    assert lay["owner_step_word"] == ls.BRIDGE_SIM_NS
    assert lay["peer_step_word"] == ls.FC_SIM_NS
    assert lay["run_mode_word"] == ls.RUN_MODE and lay["stop_word"] == ls.STOP
    assert lay["mode_lockstep"] == ls.MODE_LOCKSTEP
    assert lay["peer_sync_word"] == ls.FC_SYNC_NS
    assert lay["ring_step_word"] // 64 == seg["ring_head"] // 64     # one line per hand-off
    assert lay["ring_sync_word"] // 64 == seg["ring_head"] // 64     # the promise rides along
    assert lay["seg_handoff_arm"] % 64 == 0


def test_step_words_live_beside_the_ring_heads(name):
    # Segment.word / set_word and the C side's word pointer agree for every index.
    with Segment.create(name) as seg:
        for i in range(9):
            seg.set_word(i, 1000 + i)
        assert [seg.word(i) for i in range(9)] == [1000 + i for i in range(9)]
        with pytest.raises(Exception):
            seg.word(9)


def _fly(processes: int, log: str) -> dict:
    opts = FlightOptions(scenario="S2", duration_s=1.0, seed=7, processes=processes,
                         log_path=log, instance=f"handoff-{os.getpid()}-{processes}")
    fly = fly_one_process if processes == 1 else fly_two_processes
    return fly(opts, out=lambda line: None)


def test_two_processes_fly_what_one_process_flies(tmp_path):
    runs = {p: _fly(p, str(tmp_path / f"p{p}.mcap")) for p in (1, 2)}
    assert runs[1]["trace_hash"] == runs[2]["trace_hash"]
    logs = {p: read_log(tmp_path / f"p{p}.mcap").channels for p in (1, 2)}
    est = {p: logs[p]["/fc/status"] for p in (1, 2)}
    assert len(est[1]) == len(est[2]) > 0
    # The estimate, step by step, bit for bit (S2 sets the declination at the first fix).
    for field in ("sim_ns", "euler_est_rad", "motor_us"):
        assert np.array_equal(est[1][field], est[2][field]), field
    assert len(logs[2]["/gnss"]) > 0


# -- the bridge's batches of steps (BridgeLoop.bind_fc_process) with an FC that stalls or dies

def _spawn(args):
    return subprocess.Popen([sys.executable, "-m", "silbridge.tools", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _running(stream) -> None:
    """Read the bridge's output until its first check window (it is flying steps); with
    --json the checks go to stderr."""
    for line in stream:
        if line.startswith("check drops"):
            return
    raise AssertionError("the bridge never flew")


def _kill(*procs) -> None:
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.wait()


def test_a_stalled_fc_is_waited_for_and_the_flight_is_unchanged():
    # SIGSTOP outlasts the batch's 20 ms wait many times: the step ends its batch unanswered
    # and Python waits on (looking at the FC); the flight must be the undisturbed one.
    name = f"stall-{os.getpid()}"
    ref = _fly_json(["fly", "--processes", "2", "--duration", "120", "--seed", "5",
                     "--instance", name + "r", "--json"])
    bridge = _spawn(["bridge", "--instance", name, "--duration", "120", "--seed", "5",
                     "--json"])
    fc = _spawn(["fc", "--instance", name])
    try:
        _running(bridge.stderr)
        fc.send_signal(signal.SIGSTOP)
        time.sleep(0.3)
        fc.send_signal(signal.SIGCONT)
        out, err = bridge.communicate(timeout=120)
        assert bridge.returncode == 0, err[-2000:]
        fc.wait(timeout=30)
    finally:
        _kill(bridge, fc)
    run = json.loads([ln for ln in out.splitlines() if ln.startswith("{")][-1])
    assert run["trace_hash"] == ref["trace_hash"]


def test_a_killed_fc_stops_a_lockstep_bridge_with_a_message():
    name = f"killfc-{os.getpid()}"
    bridge = _spawn(["bridge", "--instance", name, "--duration", "600"])
    fc = _spawn(["fc", "--instance", name])
    try:
        _running(bridge.stdout)
        fc.send_signal(signal.SIGKILL)
        bridge.wait(timeout=30)
        err = bridge.stderr.read()
    finally:
        _kill(bridge, fc)
    assert bridge.returncode == 2, err[-2000:]
    assert "FC" in err


def _fly_json(args) -> dict:
    done = subprocess.run([sys.executable, "-m", "silbridge.tools", *args], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads([ln for ln in done.stdout.splitlines() if ln.startswith("{")][-1])
