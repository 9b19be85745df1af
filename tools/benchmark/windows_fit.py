"""The campaign's time windows, fitted to the run's --duration before any run starts.

The default windows (warm-up 0-10, transient 10-30, analysis 30-120, yaw 90-120 s:
tools/benchmark/metrics.py) are the paper's for a 120 s run. A shorter run would leave
the analysis window with nothing or a single sample, and a Table 1 computed from that
looks like a result (p-p 0.0 us, RMS equal to P95). So, per window:

- a window the user gave (--warmup A B, ...) is taken as given, and refused when the run
  does not cover it: we never move what was asked for;
- the default windows, when --duration is shorter than the run they were made for, are
  scaled by duration / 120 together (their proportions kept), and a line says so;
- whatever the windows, an analysis window shorter than MIN_ANALYSIS_S is refused.
"""

from __future__ import annotations

from silbridge.tools.benchmark.metrics import Windows

DEFAULTS = Windows()
# The run the default windows are made for: the paper's 120 s (their last end).
PROTOCOL_S = max(b for _, b in (DEFAULTS.warmup, DEFAULTS.transient, DEFAULTS.analysis,
                                DEFAULTS.yaw))
# The shortest analysis window scored: Table 1's statistics (P95, RMS, peak-to-peak) are
# over the 400 Hz PWM and FC-status rows; one second is 400 of them, so the P95 has 20
# samples above it instead of being the maximum of a handful.
MIN_ANALYSIS_S = 1.0

FLAGS = {"warmup": "--warmup", "transient": "--transient", "analysis": "--analysis",
         "yaw": "--yaw-window"}


class WindowError(ValueError):
    user_facing = True


def fit_windows(duration_s: float, given: dict) -> tuple[Windows, str]:
    """(the windows to score with, a note for the user or ""). given: window name ->
    (start, end) as the user typed it, or None for the default."""
    scale = min(1.0, duration_s / PROTOCOL_S)
    chosen, scaled = {}, []
    for name, flag in FLAGS.items():
        win = given.get(name)
        if win is None:
            a, b = getattr(DEFAULTS, name)
            win = (a * scale, b * scale)
            if scale < 1.0:
                scaled.append(f"{name} {win[0]:.3g}-{win[1]:.3g} s")
        else:
            a, b = (float(x) for x in win)
            if not b > a or a < 0:
                raise WindowError(f"{flag} {a:g} {b:g}: give START END with 0 <= START < END")
            if b > duration_s:
                raise WindowError(f"{flag} {a:g} {b:g} ends after the run (--duration "
                                  f"{duration_s:g} s): give a window inside 0-{duration_s:g} "
                                  f"s, or a longer --duration")
            win = (a, b)
        chosen[name] = win
    a, b = chosen["analysis"]
    if b - a < MIN_ANALYSIS_S:
        if given.get("analysis") is None:
            span = DEFAULTS.analysis[1] - DEFAULTS.analysis[0]
            fix = (f"give --duration {MIN_ANALYSIS_S * PROTOCOL_S / span:.3g} s or more "
                   f"(the default windows scale with it)")
        else:
            fix = "give a wider --analysis window"
        raise WindowError(f"analysis window {a:.3g}-{b:.3g} s is shorter than "
                          f"{MIN_ANALYSIS_S:g} s: too few samples for Table 1; {fix}")
    note = ""
    if scaled:
        note = (f"--duration {duration_s:g} s is shorter than the {PROTOCOL_S:g} s the default "
                f"windows are made for: scaled by {scale:.3g} to " + ", ".join(scaled))
    return Windows(**chosen), note
