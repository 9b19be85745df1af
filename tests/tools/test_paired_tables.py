"""The suites' comparisons use the one rule (tools/benchmark/paired_stats.py): Table 1's
ours-against-ArduCopter tables and the nav suite's, built from constructed per-run results
whose verdicts are known."""

import json
import math

import numpy as np

from silbridge.tools.benchmark.campaign import RunResult, RunSpec
from silbridge.tools.benchmark.nav.campaign import NavResult
from silbridge.tools.benchmark.nav.table import markdown as nav_markdown
from silbridge.tools.benchmark.nav.table import summarize
from silbridge.tools.benchmark.table1 import aggregate, markdown

NAN = float("nan")
SEEDS = range(1, 11)


def _run(fc: str, seed: int, **metrics) -> RunResult:
    spec = RunSpec(scenario="S1", run_index=seed - 1, seed=seed, duration_s=10.0,
                   log_path=f"/nonexistent/{fc}{seed}.mcap", fc=fc)
    return RunResult(spec=spec, metrics=metrics)


def _campaign():
    """Ours: lower p-p on every seed, higher P95 on every seed, RMS a coin toss; ArduCopter
    has no filtered gyro (NaN); ArduCopter's seed 10 did not finish, ours' seed 3 has no P95."""
    rng = np.random.default_rng(0)
    out = []
    for s in SEEDS:
        hard = 3.0 * s                  # what the seed does to both controllers
        out.append(_run("ours", s, pwm_pp_us=hard + 4.0, att_p95_deg=NAN if s == 3 else 0.9,
                        att_rms_deg=0.5 + rng.normal(0, 0.05), gyro_noise_dps=0.2,
                        motor_noise_us=2.0))
        if s != 10:
            out.append(_run("ardupilot", s, pwm_pp_us=hard + 5.0 + rng.normal(0, 0.1),
                            att_p95_deg=0.8, att_rms_deg=0.5 + rng.normal(0, 0.05),
                            gyro_noise_dps=NAN, motor_noise_us=2.0))
    return out


def test_table1_pairs_ours_with_arducopter_by_seed():
    table = aggregate(_campaign())
    [c] = table["comparison"]["comparisons"]
    assert (c["scenario"], c["fc"]) == ("S1", "ardupilot")
    m = c["metrics"]
    assert m["pwm_pp_us"]["verdict"] == "at_or_below" and m["pwm_pp_us"]["n"] == 9
    assert m["att_p95_deg"]["verdict"] == "loses" and m["att_p95_deg"]["text"] == \
        "loses by 0.100 deg"
    assert m["att_rms_deg"]["verdict"] == "tie"
    assert m["motor_noise_us"]["verdict"] == "at_or_below"       # equal on every seed
    assert "gyro_noise_dps" in c["not_compared"] and "gyro_noise_dps" not in m
    assert c["unpaired_runs"] == {"ours": [10], "ardupilot": []}
    assert m["att_p95_deg"]["unpaired_a"] == [10]                 # seed 3's NaN: unpaired too
    assert m["att_p95_deg"]["unpaired_b"] == [3] and m["att_p95_deg"]["n"] == 8
    json.dumps(table)                                             # table1.json stays JSON


def test_table1_markdown_prints_the_verdicts_and_the_unpaired_runs():
    md = markdown(aggregate(_campaign()))
    assert "**Ours against ArduCopter, paired by seed**" in md
    row = next(line for line in md.splitlines() if line.startswith("| S1 | P95 (deg)"))
    assert row.endswith("| 8 | loses by 0.100 deg |")
    assert "seed 10 flown by ours only: not paired" in md
    assert "S1 P95: seed 3 has a value for ArduCopter only: not paired" in md
    assert "not compared" in md and "gyro noise" in md
    assert "10,000 resamples" in md


def test_one_controller_gives_no_comparison():
    table = aggregate([r for r in _campaign() if r.spec.fc == "ours"])
    assert "comparison" not in table and "paired" not in markdown(table)


def test_the_nav_suite_pairs_by_seed_and_leaves_failed_runs_unpaired():
    results = []
    for s in SEEDS:
        results.append(NavResult("N1", "ours", s, "ok",
                                 metrics={"overshoot_m": 0.2 + 0.01 * s, "arrive_s": 9.0,
                                          "peak_speed_m_s": 5.0}))
        ok = s != 7
        results.append(NavResult("N1", "ardupilot", s, "ok" if ok else "failed",
                                 reason="" if ok else "timed out",
                                 metrics={"overshoot_m": 0.5 + 0.01 * s, "arrive_s": 8.0,
                                          "peak_speed_m_s": 6.0} if ok else {}))
    summary = summarize(results, ["ours", "ardupilot"])
    p = summary["N1"]["paired"]["ardupilot"]
    assert p["overshoot_m"]["verdict"] == "at_or_below" and p["overshoot_m"]["n"] == 9
    assert p["arrive_s"]["verdict"] == "loses"
    assert p["peak_speed_m_s"]["verdict"] == "none"               # no better side
    assert p["overshoot_m"]["unpaired_a"] == [7]
    md = nav_markdown(summary, ["ours", "ardupilot"], len(SEEDS))
    assert "| N1 | time to arrive within 1 m, mean of legs [s] |" in md
    assert "loses by 1 s" in md
    assert "seed 7 has a value for ours only: not paired" in md
    assert math.isclose(p["overshoot_m"]["median_diff"], -0.3)


def test_the_same_rule_pairs_other_sides_such_as_ablation_variants():
    from dataclasses import replace

    from silbridge.tools.benchmark.table1_compare import comparison_markdown, compare_fcs

    results = []
    for s in SEEDS:
        for variant, pp in (("full", 5.0), ("no_pt2", 9.0)):
            r = _run("ours", s, pwm_pp_us=pp + 0.1 * s)
            results.append(replace(r, spec=replace(r.spec, variant=variant)))
    comp = compare_fcs(results, lambda r: r.spec.scenario, base="full",
                       side_of=lambda r: r.spec.variant)
    [c] = comp["comparisons"]
    assert c["fc"] == "no_pt2" and c["metrics"]["pwm_pp_us"]["verdict"] == "at_or_below"
    assert c["unpaired_runs"] == {"full": [], "no_pt2": []}
    assert "**Full against no_pt2, paired by seed**" in comparison_markdown(comp)
