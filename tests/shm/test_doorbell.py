"""The lockstep doorbell (shm/include/sb_doorbell.h): a waiting process blocks on a futex in
the segment, gives its core away, and is woken the moment its peer publishes; a publisher
with nobody waiting makes no system call."""

from __future__ import annotations

import json
import subprocess
import sys
import time

from silbridge.shm import Segment

# The peer: attach, wait (up to 20 s) for word 3 >= 1, report how long and at what CPU cost.
_WAITER = """
import json, sys, time
from silbridge.shm import Segment
seg = Segment.attach(sys.argv[1], timeout_s=10)
seg.set_word(4, 1)                          # "about to wait"
cpu0 = time.process_time()
ok = seg.wait_word(3, 1, 20.0)
woke = time.monotonic_ns()
print(json.dumps({"ok": ok, "woke_ns": woke, "cpu_s": time.process_time() - cpu0}), flush=True)
seg.close()
"""


def _info_until(seg, cond, timeout_s=20.0):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        info = seg.info
        if cond(info):
            return info
        time.sleep(0.01)
    raise AssertionError(f"condition not reached: {seg.info}")


def test_a_waiting_peer_blocks_and_is_woken_at_once(name):
    with Segment.create(name) as seg:
        child = subprocess.Popen([sys.executable, "-c", _WAITER, name], stdout=subprocess.PIPE,
                                 text=True)
        try:
            # The peer announces itself on the owner's doorbell once its spin phase is over.
            _info_until(seg, lambda i: i["bell_waiters"][0] == 1 and seg.word(4) == 1)
            time.sleep(1.0)                   # a second of blocking: no CPU burnt
            wakes_before = seg.info["bell_wakes"][0]
            published = time.monotonic_ns()
            seg.set_word(3, 1)
            out, _ = child.communicate(timeout=20)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        r = json.loads(out)
        assert r["ok"]
        # Woken by the publish (generous: a loaded 2-core runner), not by the 20 s timeout.
        assert (r["woke_ns"] - published) / 1e9 < 1.0
        # Over a second of waiting it burnt a few ms of CPU (spinning or yielding: ~1 s).
        assert r["cpu_s"] < 0.3, r
        assert seg.info["bell_wakes"][0] == wakes_before + 1
        assert seg.info["bell_waiters"][0] == 0


def test_publishing_with_nobody_waiting_makes_no_wake_call(name):
    with Segment.create(name) as seg:
        for v in range(10_000):
            seg.set_word(0, v)
        assert seg.info["bell_wakes"] == (0, 0)
        assert seg.info["bell_waiters"] == (0, 0)


def test_wait_times_out_when_nobody_publishes(name):
    with Segment.create(name) as seg:
        t0 = time.monotonic()
        assert not seg.wait_word(3, 1, 0.2)
        assert 0.15 < time.monotonic() - t0 < 5.0
        assert seg.info["bell_waiters"] == (0, 0)
