"""The real-time pacer (bridge/pacing.py) holds its deadlines and lets the process's other
threads run while it spins: a one-process `fly --realtime` serves MAVLink on a thread of its
own, and at --speed 5 and up the pacer spins through every period."""

from __future__ import annotations

import sys
import threading
import time

from silbridge.bridge.pacing import Pacer

_NS = 1_000_000_000


def test_a_spinning_pacer_lets_another_thread_take_the_gil():
    # A period (100 us) shorter than the spin margin (200 us): the pacer never sleeps. With
    # the switch interval at 50 ms, a spin that kept the GIL would let the sleeping thread in
    # at most once per 50 ms (~6 times in 0.3 s); a spin without it, after every 1 ms nap.
    pacer = Pacer(dt_ns=1_000_000, speed=10.0)
    woke = []
    done = threading.Event()

    def napper():
        while not done.is_set():
            time.sleep(0.001)
            woke.append(1)

    old = sys.getswitchinterval()
    sys.setswitchinterval(0.05)
    t = threading.Thread(target=napper)
    try:
        t.start()
        pacer.restart()
        k = 0
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            k += 1
            pacer.wait_for_step(k)
    finally:
        done.set()
        t.join()
        sys.setswitchinterval(old)
    print(f"\n{len(woke)} naps in 0.3 s beside a pacer spinning {k} steps")
    assert len(woke) > 30, len(woke)


def test_deadlines_are_kept_and_a_late_step_is_counted():
    pacer = Pacer(dt_ns=1_000_000, speed=1.0)
    pacer.restart()
    for k in range(1, 21):
        late = pacer.wait_for_step(k)
        now = time.monotonic_ns()
        assert now >= pacer.start_ns + k * 1_000_000      # never early
        assert late >= 0
    time.sleep(0.01)                                      # ten periods behind
    late = pacer.wait_for_step(21)
    assert late > 5 * 1_000_000
    assert pacer.late_steps >= 1 and pacer.max_late_ns >= late
