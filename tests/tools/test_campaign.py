"""The campaign: reproducible tables, local vs Ray executors, ablation variants."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from silbridge.fc_sil.params import ABLATION_FEATURES, FEATURES, feature_params
from silbridge.tools.benchmark.ablation import variants
from silbridge.tools.benchmark.campaign import make_specs, run_campaign
from silbridge.tools.benchmark.table1 import aggregate, markdown

SHORT = dict(runs=2, duration_s=12.0)
WINDOWS = ((0.0, 5.0), (5.0, 7.0), (7.0, 12.0), (9.0, 12.0))


def _table(tmp_path, executor="local", jobs=2, scenarios=("S1", "S3")):
    specs = make_specs(list(scenarios), SHORT["runs"], SHORT["duration_s"], tmp_path,
                       windows=WINDOWS)
    results = run_campaign(specs, jobs=jobs, executor=executor, progress=False)
    return aggregate(results), results


def test_same_campaign_twice_gives_identical_tables(tmp_path):
    a, ra = _table(tmp_path / "a")
    b, rb = _table(tmp_path / "b", jobs=1)
    # Wall-clock figures (latency, jitter, loop period) differ run to run by nature.
    wall = ("latency", "jitter", "period", "wall", "realtime")

    def deterministic(t):
        return {s: {k: v for k, v in m.items() if not any(w in k for w in wall)}
                for s, m in t["scenarios"].items()}
    assert deterministic(a) == deterministic(b)
    assert [r.summary["trace_hash"] for r in ra] == [r.summary["trace_hash"] for r in rb]
    for name in ("S1", "S3"):
        assert a["scenarios"][name]["att_rms_deg"]["n"] == 2
    md = markdown(a)
    assert "S1 paper" in md and "1.227" in md


def test_ray_executor_matches_local(tmp_path):
    pytest.importorskip("ray")
    local, rl = _table(tmp_path / "local", scenarios=("S1",))
    ray_t, rr = _table(tmp_path / "ray", executor="ray", scenarios=("S1",))
    assert [r.summary["trace_hash"] for r in rl] == [r.summary["trace_hash"] for r in rr]
    assert local["scenarios"]["S1"]["att_rms_deg"] == ray_t["scenarios"]["S1"]["att_rms_deg"]
    assert local["scenarios"]["S1"]["pwm_pp_us"] == ray_t["scenarios"]["S1"]["pwm_pp_us"]


def test_ablation_variants_switch_real_parameters():
    labels = [v[0] for v in variants()]
    assert labels[0] == "full" and labels[-2:] == ["all_off", "defaults"]
    assert labels[1:-2] == [f"no_{f}" for f in ABLATION_FEATURES]
    assert feature_params(["slew"]) == {"SB_SLEW_EN": 0}
    assert feature_params(["d_filter"]) == {"SB_DFILT_EN": 0}   # the documented names
    with pytest.raises(ValueError, match="unknown feature"):
        feature_params(["warp_drive"])
    from silbridge.fc_sil.flight_core import FlightCore
    core = FlightCore()
    for name in FEATURES.values():
        assert core.get_param(name) in (0, 1)   # every switch exists in the FC


def test_ablation_full_is_the_papers_controller_whatever_the_defaults():
    """`full` switches every paper feature on explicitly, `no_X` all but X, `all_off` none,
    so the study shows what each feature pays even when the ablation has switched its
    default off; `defaults` leaves the declared defaults alone."""
    from silbridge.fc_sil.params import BY_NAME
    paper = {FEATURES[f] for f in ABLATION_FEATURES}
    off_by_default = {n for n in paper if BY_NAME[n].default == 0}
    assert off_by_default   # the case this test is about: some defaults are off
    v = dict(variants())
    assert v["full"] == {n: 1 for n in paper}
    assert v["all_off"] == {n: 0 for n in paper}
    assert v["defaults"] == {}
    for f in ABLATION_FEATURES:
        assert v[f"no_{f}"] == {n: int(n != FEATURES[f]) for n in paper}
    # What the FC flies: the variant's switches over the defaults, and over a --param.
    from silbridge.fc_sil.flight_core import FlightCore
    core = FlightCore()
    assert {n for n in paper if core.get_param(n) == 0} == off_by_default
    given = dict(variants([("SB_DFILT_EN", 0), ("ATC_RAT_RLL_D", 0.004)]))
    assert given["full"]["SB_DFILT_EN"] == 1 and given["full"]["ATC_RAT_RLL_D"] == 0.004
    assert given["defaults"] == {"SB_DFILT_EN": 0, "ATC_RAT_RLL_D": 0.004}
    for name, value in given["full"].items():
        core.set_param(name, value)
    assert all(core.get_param(n) == 1 for n in paper)


def test_bench_cli_json_shape(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "silbridge.tools", "bench", "--scenarios", "S1", "--runs", "1",
         "--duration", "8", "--warmup", "0", "4", "--transient", "4", "5", "--analysis", "5",
         "8", "--yaw-window", "6", "8", "--out", str(tmp_path), "--json", "--jobs", "1"],
        capture_output=True, text=True, check=True).stdout
    table = json.loads(out)
    stat = table["scenarios"]["S1"]["att_rms_deg"]
    assert set(stat) == {"mean", "std", "n"} and stat["n"] == 1
    assert (tmp_path / "report" / "index.html").exists()
    assert (tmp_path / "table1.md").exists()


def test_bench_refuses_bad_arguments(tmp_path):
    p = subprocess.run([sys.executable, "-m", "silbridge.tools", "bench", "--runs", "0",
                        "--out", str(tmp_path)], capture_output=True, text=True)
    assert p.returncode == 2 and "--runs" in p.stderr


def test_table_cells_never_show_a_negative_zero():
    from silbridge.tools.benchmark.table1 import _cell
    assert _cell({"mean": -0.0003, "std": 0.0004}, "{:.2f}") == "0.00 ± 0.00"
    assert _cell({"mean": -0.3, "std": 0.1}, "{:.2f}") == "-0.30 ± 0.10"
    assert _cell(None, "{:.2f}") == "n/a"


def test_blend_ablation_on_a4_switches_the_source_in_flight(tmp_path):
    # A4 switches SB_ATT_SRC to ground truth at 25 s: score 24-27 s, blend on and off.
    windows = ((0.0, 10.0), (10.0, 24.0), (24.0, 27.0), (25.0, 27.0))
    specs = []
    for label, off in (("full", ()), ("no_blend", ("blend",))):
        specs += make_specs(["A4"], 1, 27.0, tmp_path, features_off=off, variant=label,
                            windows=windows)
    full, no_blend = run_campaign(specs, jobs=1, progress=False)
    assert full.summary["trace_hash"] != no_blend.summary["trace_hash"]
    # The hard switch is a step of the attitude error: the motors see it.
    assert no_blend.metrics["pwm_pp_us"] > full.metrics["pwm_pp_us"]
