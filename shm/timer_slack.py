"""Timer slack: how late the kernel may wake a sleeping thread, to batch wake-ups.

Linux defaults to 50 us per thread. A real-time loop that sleeps most of each period and
spins the rest (bridge/pacing.py) or waits on its ring (fc_sil/fc_loop.py) wants exact
wake-ups: with 1 ns, a 0.5 ms sleep on the 2-core VM overshot by p50 49 us / p99 105 us
instead of 93 / 151 us (measured 2026-11-22, python -c "time.sleep(0.0005)" x 3000).
Only the calling thread changes; elsewhere (not Linux) this does nothing.
"""

from __future__ import annotations

import ctypes
import sys

_PR_SET_TIMERSLACK = 29


def set_timer_slack_ns(ns: int = 1) -> bool:
    """Set this thread's timer slack; True when the kernel took it."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_TIMERSLACK, ctypes.c_ulong(max(1, int(ns))), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False
