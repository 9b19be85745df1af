"""The bridge micro-benchmark's outputs (figures are reported, never asserted)."""

import pytest

from silbridge.bridge.bench import bench, bench_stalls


def test_step_bench_reports_its_figures():
    r = bench(1000, steps=200, reps=1)
    # Both timed, and the overhead is their difference; which is larger is a measurement
    # (200 steps on a busy machine can put JSBSim alone above the whole step), not asserted.
    assert r["us_per_step"] > 0 and r["jsbsim_run_us"] > 0
    assert r["bridge_overhead_us"] == pytest.approx(r["us_per_step"] - r["jsbsim_run_us"])
    assert r["realtime_factor"] == pytest.approx(1e3 / r["us_per_step"])


def test_stall_census_counts_nested_thresholds():
    s = bench_stalls(0.2)
    counts = [s[f"over_{t}us"]["count"] for t in (20, 50, 100, 500)]
    assert counts == sorted(counts, reverse=True)          # a gap over 100 us is over 50 too
    assert all(0.0 <= s[f"over_{t}us"]["windows_pct"] <= 100.0 for t in (20, 50, 100, 500))
