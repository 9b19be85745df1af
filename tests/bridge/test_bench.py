"""The bridge micro-benchmark's outputs (figures are reported, never asserted)."""

from silbridge.bridge.bench import bench, bench_stalls


def test_step_bench_reports_its_figures():
    r = bench(1000, steps=200, reps=1)
    assert r["us_per_step"] > r["jsbsim_run_us"] > 0
    assert r["realtime_factor"] > 0


def test_stall_census_counts_nested_thresholds():
    s = bench_stalls(0.2)
    counts = [s[f"over_{t}us"]["count"] for t in (20, 50, 100, 500)]
    assert counts == sorted(counts, reverse=True)          # a gap over 100 us is over 50 too
    assert all(0.0 <= s[f"over_{t}us"]["windows_pct"] <= 100.0 for t in (20, 50, 100, 500))
