"""The soak verdict on synthetic series: growth that must fail, steadiness that must pass."""

from __future__ import annotations

import numpy as np

from silbridge.tools.soak.log_minutes import minutes_from_timing
from silbridge.tools.soak.verdict import (
    check_fds,
    check_late_trend,
    check_rss,
    theil_sen_slope,
    verdict,
    warmup_s,
)

HOUR = 3600.0
MINUTES = [60.0 * i for i in range(1, 61)]


def test_rss_that_settles_after_the_warmup_passes():
    # 100 MB climbing to 124 MB in the first 5 minutes (samples at 1..5 min), then flat
    # within 2 %
    rss = [100_000 + 6_000 * min(i, 4) + (2_000 if i % 7 == 0 else 0) for i in range(60)]
    ok, detail = check_rss("bridge", MINUTES, rss, HOUR)
    assert ok, detail


def test_rss_that_keeps_growing_fails():
    # 0.2 % a minute after the warm-up: about 11 % by the end of the hour
    rss = [100_000 * (1 + 0.002 * i) for i in range(60)]
    ok, detail = check_rss("fc", MINUTES, rss, HOUR)
    assert not ok and "fc" in detail


def test_short_runs_warm_up_for_a_quarter():
    assert warmup_s(HOUR) == 300.0
    assert warmup_s(120.0) == 30.0
    t = [15.0 * i for i in range(1, 9)]
    # a jump in the first 30 s of a 2-minute run is warm-up; the same jump later is growth
    assert check_rss("x", t, [100, 120, 120, 120, 121, 121, 121, 121], 120.0)[0]
    assert not check_rss("x", t, [100, 100, 100, 120, 120, 120, 120, 120], 120.0)[0]


def test_fds_must_stay_constant_after_the_warmup():
    assert check_fds("bridge", MINUTES, [4, 5] + [5] * 58, HOUR)[0]
    leak = [5] * 30 + [6] * 30
    ok, detail = check_fds("bridge", MINUTES, leak, HOUR)
    assert not ok and "5..6" in detail


def test_late_steps_that_come_and_go_are_no_trend():
    rng = np.random.default_rng(1)
    late = list(rng.poisson(300, 60).astype(float))
    late[20] = late[21] = 9000.0            # another job's burst: one outlier pair
    assert check_late_trend(MINUTES, late)[0]


def test_late_steps_that_climb_are_a_trend():
    late = [10.0 * i for i in range(60)]     # 0 -> 590 a minute over the hour
    ok, detail = check_late_trend(MINUTES, late)
    assert not ok, detail


def test_a_trend_needs_enough_intervals():
    assert not check_late_trend([0.0, 60.0], [0.0, 0.0])[0]


def test_theil_sen_ignores_one_outlier():
    xs = list(range(11))
    ys = [2.0 * x for x in xs]
    ys[5] = 1000.0
    assert theil_sen_slope(xs, ys) == 2.0


def _samples(rss_bridge, fds_fc):
    return [{"t_s": t, "procs": {"bridge": {"rss_kb": r, "fds": 5},
                                 "fc": {"rss_kb": 50_000, "fds": f}}}
            for t, r, f in zip(MINUTES, rss_bridge, fds_fc, strict=True)]


def _flat_minutes():
    return [{"t_s": t, "late_steps_per_min": 100.0} for t in MINUTES]


def test_verdict_passes_a_steady_run_and_names_each_check():
    v = verdict(_samples([40_000] * 60, [8] * 60), _flat_minutes(), HOUR)
    assert v["ok"], v
    names = [c["name"] for c in v["checks"]]
    assert names == ["rss bridge", "fds bridge", "rss fc", "fds fc", "late trend", "gcs actions"]


def test_verdict_fails_on_any_one_check():
    leak = _samples([40_000 * (1 + 0.003 * i) for i in range(60)], [8] * 60)
    assert not verdict(leak, _flat_minutes(), HOUR)["ok"]
    assert not verdict(_samples([40_000] * 60, [8] * 60), _flat_minutes(), HOUR,
                       actions_failed=1)["ok"]
    vanished = _samples([40_000] * 60, [8] * 60)
    del vanished[40]["procs"]["fc"]
    v = verdict(vanished, _flat_minutes(), HOUR)
    assert not v["ok"] and "process fc" in [c["name"] for c in v["checks"] if not c["ok"]]


def test_minutes_from_timing_counts_late_samples_and_rates():
    # 1 kHz for 3 minutes, on time except 50 samples in minute 1 that are 3 ms late
    n = 180_000
    sim = np.arange(n, dtype=np.int64) * 1_000_000
    wall = sim + 5_000_000_000
    wall[70_000:70_050] += 3_000_000
    pwm = np.where(np.arange(n) % 5 < 2, wall + 100, 0)     # 400 Hz of 1000
    m = minutes_from_timing(wall, sim, pwm, period_ns=1e6)
    assert [x["late_steps"] for x in m] == [0, 50]           # the last, partial minute left out
    assert m[0]["imu_hz"] == 1000.0 and m[0]["pwm_hz"] == 400.0
    assert m[1]["late_steps_per_min"] == 50.0
