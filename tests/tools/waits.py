"""Client-side waits the ground-station tests share: poll a condition on the wall clock (a
stalled autopilot fails the test instead of hanging it), and ask again what an autopilot may
refuse for a while (ArduCopter refuses to arm until its EKF has settled)."""

from __future__ import annotations

import time


def until(pred, timeout_s: float, step_s: float = 0.2):
    """pred()'s first true value within timeout_s, polled every step_s; None on timeout."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(step_s)
    return None


def accepted(fn) -> bool:
    """True if fn() returned, False if it raised (the autopilot refused: ask again later)."""
    try:
        fn()
        return True
    except Exception:
        return False
