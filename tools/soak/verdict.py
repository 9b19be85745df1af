"""The soak verdict: pure functions over the sampled series (no processes, no clocks).

Each check returns (ok, one-line detail). Kept apart from the sampling so the unit tests
can feed synthetic series that must pass and must fail (tests/tools/test_soak_verdict.py).
"""

from __future__ import annotations

# Targets of issue 29: RSS within 5 % of its value after the warm-up, the same number of
# open files throughout, and no upward trend in late steps per minute.
RSS_GROWTH_MAX = 0.05
WARMUP_S = 300.0                 # the first 5 minutes: allocations that settle once
WARMUP_FRACTION_SHORT = 0.25     # short runs (under 4 warm-ups long) warm up for a quarter
# A late-step trend: the run's robust line (Theil-Sen, so one burst of other work on the
# machine does not make a trend) rises over the whole run by more than one late step per
# second, and by more than half the run's median level (late steps come and go with the
# machine's load; a trend is what grows, not what is there from the start).
LATE_RISE_ABS_PER_MIN = 60.0
LATE_RISE_REL = 0.5
MIN_SAMPLES_FOR_TREND = 5


def warmup_s(total_s: float) -> float:
    """How long allocations may settle before RSS is held to its bound."""
    if total_s >= 4 * WARMUP_S:
        return WARMUP_S
    return total_s * WARMUP_FRACTION_SHORT


def baseline_index(times_s: list[float], warm_s: float) -> int:
    """The first sample at or after the warm-up (the last one if none is)."""
    for i, t in enumerate(times_s):
        if t >= warm_s:
            return i
    return max(0, len(times_s) - 1)


def rss_growth(rss_kb: list[float], base: int) -> float:
    """Largest RSS after the baseline sample, relative to it (0.03 = 3 % growth)."""
    if not rss_kb or rss_kb[base] <= 0:
        return 0.0
    return max(rss_kb[base:]) / rss_kb[base] - 1.0


def check_rss(name: str, times_s: list[float], rss_kb: list[float], total_s: float):
    base = baseline_index(times_s, warmup_s(total_s))
    g = rss_growth(rss_kb, base)
    ok = g <= RSS_GROWTH_MAX
    return ok, (f"RSS {name}: {rss_kb[base] / 1024:.1f} MB at {times_s[base]:.0f} s -> peak "
                f"{max(rss_kb[base:]) / 1024:.1f} MB after ({g:+.1%}, limit "
                f"{RSS_GROWTH_MAX:+.0%})")


def check_fds(name: str, times_s: list[float], fds: list[int], total_s: float):
    """Open files: constant after the warm-up (the log, sockets and rings open at start)."""
    base = baseline_index(times_s, warmup_s(total_s))
    after = fds[base:]
    ok = len(set(after)) <= 1
    return ok, (f"fds {name}: {after[0]} from {times_s[base]:.0f} s" if ok else
                f"fds {name}: {min(after)}..{max(after)} after {times_s[base]:.0f} s "
                f"(want one constant count)")


def median(v: list[float]) -> float:
    v = sorted(v)
    n = len(v)
    if n == 0:
        return 0.0
    return v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2


def theil_sen_slope(xs: list[float], ys: list[float]) -> float:
    """Median of the pairwise slopes: a line one outlier cannot tilt (0 if undefined)."""
    if len(xs) != len(ys):
        raise ValueError(f"{len(xs)} xs for {len(ys)} ys")
    pairs = [(ys[j] - ys[i]) / (xs[j] - xs[i]) for i in range(len(xs))
             for j in range(i + 1, len(xs)) if xs[j] != xs[i]]
    return median(pairs)


def check_late_trend(times_s: list[float], late_per_min: list[float]):
    """No upward trend in late steps per minute over the run."""
    if len(late_per_min) < MIN_SAMPLES_FOR_TREND:
        return False, (f"late steps: {len(late_per_min)} intervals, a trend needs "
                       f"{MIN_SAMPLES_FOR_TREND}: run longer or sample more often")
    span_s = times_s[-1] - times_s[0]
    rise = theil_sen_slope(times_s, late_per_min) * span_s
    level = median(late_per_min)
    limit = max(LATE_RISE_ABS_PER_MIN, LATE_RISE_REL * level)
    ok = rise <= limit
    return ok, (f"late steps/min: median {level:.0f}, trend {rise:+.0f}/min over "
                f"{span_s / 60:.0f} min (limit {limit:+.0f})")


def verdict(samples: list[dict], minutes: list[dict], total_s: float,
            actions_failed: int = 0) -> dict:
    """All checks: {"ok": bool, "checks": [{"name", "ok", "detail"}]}.

    samples: dicts with "t_s" and "procs" {name: {"rss_kb", "fds"}}; minutes: dicts with
    "t_s" and "late_steps_per_min" (one per interval of the run's log); actions_failed: the
    ground station's failed actions (a soak whose GCS breaks is a failed soak).
    """
    checks = []
    if len(samples) < 2:
        checks.append(("samples", False, f"{len(samples)} samples: the run ended too early"))
    else:
        names = sorted(set().union(*(s["procs"] for s in samples)))
        for name in names:
            rows = [(s["t_s"], s["procs"][name]) for s in samples if name in s["procs"]]
            if len(rows) != len(samples):
                checks.append((f"process {name}", False,
                               f"{name}: present in {len(rows)} of {len(samples)} samples"))
                continue
            ts = [r[0] for r in rows]
            checks.append((f"rss {name}", *check_rss(name, ts, [r[1]["rss_kb"] for r in rows],
                                                     total_s)))
            checks.append((f"fds {name}", *check_fds(name, ts, [r[1]["fds"] for r in rows],
                                                     total_s)))
    checks.append(("late trend", *check_late_trend([m["t_s"] for m in minutes],
                                                    [m["late_steps_per_min"] for m in minutes])))
    checks.append(("gcs actions", actions_failed == 0,
                   f"ground-station actions failed: {actions_failed}"))
    return {"ok": all(c[1] for c in checks),
            "checks": [{"name": n, "ok": ok, "detail": d} for n, ok, d in checks]}
