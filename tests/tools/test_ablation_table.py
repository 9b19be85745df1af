"""The ablation judges each variant against the full controller by the one paired rule
(tools/benchmark/ablation_table.py), from constructed runs whose verdicts are known; and the
notch's variants join only when the campaign flies a notch."""

import json

import numpy as np
import pytest
from dataclasses import replace

from silbridge.tools.benchmark import ablation_table
from silbridge.tools.benchmark.ablation import lowpass_for, notch_changes, variants
from silbridge.tools.benchmark.campaign import RunResult, RunSpec

SEEDS = range(1, 8)


def _run(variant: str, seed: int, scenario: str = "V2", **metrics) -> RunResult:
    spec = RunSpec(scenario=scenario, run_index=seed - 1, seed=seed, duration_s=10.0,
                   log_path=f"/nonexistent/{variant}{seed}.mcap", variant=variant)
    return RunResult(spec=spec, metrics=metrics)


def _campaign():
    """What a seed does to both sides dominates the spread (3 us per seed), so only pairing
    sees that no_slew costs 1 us of p-p on every seed; means would call it noise. no_trust_ema
    is a coin toss; no_d_filter's seed 4 did not finish."""
    rng = np.random.default_rng(1)
    out = []
    for s in SEEDS:
        hard = 3.0 * s
        out.append(_run("full", s, pwm_pp_us=hard + 4.0, att_rms_deg=0.5, gyro_noise_dps=0.2))
        out.append(_run("no_slew", s, pwm_pp_us=hard + 5.0, att_rms_deg=0.5,
                        gyro_noise_dps=0.2))
        out.append(_run("no_trust_ema", s, pwm_pp_us=hard + 4.0 + rng.normal(0, 0.5),
                        att_rms_deg=0.5, gyro_noise_dps=0.2))
        if s != 4:
            out.append(_run("no_d_filter", s, pwm_pp_us=hard + 3.5, att_rms_deg=0.6,
                            gyro_noise_dps=float("nan")))
    return out


def _judged():
    rows = ablation_table.run_rows(_campaign(), lambda r: r.spec.scenario)
    return rows, ablation_table.payload(rows)


def test_each_variant_is_paired_with_full_by_seed():
    rows, p = _judged()
    v = p["paired"]
    pp = v["no_slew"]["V2"]["pwm_pp_us"]
    assert pp["verdict"] == "loses" and pp["text"] == "loses by 1 us" and pp["n"] == 7
    assert pp["ci95"] == [1.0, 1.0]
    assert v["no_trust_ema"]["V2"]["pwm_pp_us"]["verdict"] == "tie"
    d = v["no_d_filter"]["V2"]
    assert d["pwm_pp_us"]["verdict"] == "at_or_below" and d["pwm_pp_us"]["n"] == 6
    assert d["pwm_pp_us"]["unpaired_b"] == [4]         # full flew seed 4, the variant did not
    assert d["att_rms_deg"]["text"] == "loses by 0.1 deg"
    assert d["gyro_noise_dps"]["verdict"] == "no_pairs"
    assert "full" not in v and p["method"]["pairing"] == "seed"


def test_the_table_rebuilds_from_its_json_alone():
    rows, p = _judged()
    md = ablation_table.markdown(rows, p["paired"])
    back = json.loads(json.dumps(p))
    assert ablation_table.markdown(back["runs"], back["paired"]) == md
    glance, detail = [line for line in md.splitlines() if line.startswith("| no_slew |")][:2]
    assert glance.startswith("| no_slew | loses by 1 us | at or below |")   # p-p, RMS
    assert detail == "| no_slew | 1 [1, 1]: loses by 1 us |"
    assert "| full (median) | 16 |" in md
    assert "| no_d_filter | n/a |" in md          # gyro noise: the variant has none
    assert "*D-term noise" not in md               # a metric no run carries is left out


def test_notch_variants_join_only_when_the_campaign_flies_a_notch():
    plain = [label for label, _ in variants()]
    assert not any(label.startswith("notch") for label in plain)
    notch = dict(variants({"INS_HNTCH_ENABLE": 1, "INS_HNTCH_FREQ": 81, "INS_HNTCH_ATT": 40}))
    assert notch["full"]["INS_HNTCH_ENABLE"] == 1
    assert notch["notch_off"] == {**notch["full"], "INS_HNTCH_ENABLE": 0}
    assert notch["notch_lowpass"] == {**notch["full"], "INS_HNTCH_ENABLE": 0,
                                      "INS_GYRO_FILTER": 8}
    assert notch["notch_fft"]["INS_HNTCH_MODE"] == 4 and notch["notch_fft"]["FFT_ENABLE"] == 1
    labels = [label for label, _ in notch_changes({})]
    assert labels == ["notch_off", "notch_lowpass", "notch_fft"]


def test_the_plain_lowpass_attenuates_the_notch_centre_as_deeply_as_the_notch():
    signal = pytest.importorskip("scipy.signal")
    for freq, att in ((81.0, 40.0), (160.0, 30.0)):
        fc = freq / (10 ** (att / 10) - 1) ** 0.25            # before rounding to whole Hz
        b, a = signal.butter(2, 2 * np.pi * fc, analog=True)
        _, h = signal.freqs(b, a, worN=[2 * np.pi * freq])
        assert 20 * np.log10(abs(h[0])) == pytest.approx(-att, abs=1e-6)
        assert lowpass_for(freq, att) == round(fc)


def test_run_rows_keep_numbers_only():
    r = _run("full", 1, pwm_pp_us=4.0, crashed=False, note="x")
    [row] = ablation_table.run_rows([replace(r)], lambda r: r.spec.scenario)
    assert row == {"variant": "full", "scenario": "V2", "seed": 1,
                   "metrics": {"pwm_pp_us": 4.0}}


def test_a_metric_the_log_cannot_give_is_null_in_the_json():
    [row] = ablation_table.run_rows([_run("full", 1, gyro_noise_dps=float("nan"))],
                                    lambda r: r.spec.scenario)
    assert row["metrics"] == {"gyro_noise_dps": None}
    json.dumps(row, allow_nan=False)
