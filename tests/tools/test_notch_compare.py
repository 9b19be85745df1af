"""Our notch against ArduCopter's and PX4's (tools/benchmark/notch_compare.py,
tools/docs/notch_page.py): the parameters each side gets, runs flown in parts merged by seed,
each foreign side paired with ours set up the same way, and the page's verdicts, from
constructed runs whose verdicts are known (the flights themselves: docs/notch-vs-arducopter.md)."""

import math

import pytest

from silbridge.tools.benchmark import notch_compare as nc
from silbridge.tools.benchmark.campaign import RunResult, RunSpec
from silbridge.tools.docs import notch_page

NOTCH = {"INS_HNTCH_ENABLE": 1, "INS_HNTCH_MODE": 1, "INS_HNTCH_FREQ": 81,
         "INS_HNTCH_BW": 40.5, "INS_HNTCH_REF": 0.516}


def test_arducopter_gets_our_numbers_and_once_its_own_throttle_unit():
    sides = nc.side_params(NOTCH, expo=0.65)
    assert sides["ours"] == sides["ardupilot"] == NOTCH
    ref = sides["ardupilot_ref"]["INS_HNTCH_REF"]
    assert ref == pytest.approx(0.354, abs=1e-3)
    # At hover ArduCopter's throttle_out is that thrust; with our REF its notch would sit at
    # FREQ x sqrt(thrust / REF), 67 Hz for V2's 81 Hz line; with its own REF at FREQ.
    assert 81 * math.sqrt(ref / 0.516) == pytest.approx(67.1, abs=0.2)
    assert nc.hover_thrust(1.0, 0.65) == 1.0 and nc.hover_thrust(0.5, 0.0) == 0.5


def test_read_parm_skips_comments(tmp_path):
    parm = tmp_path / "notch.parm"
    parm.write_text("# tune notch\nINS_HNTCH_FREQ   81\nINS_HNTCH_BW 40.5  # half\n\n")
    assert nc.read_parm(parm) == {"INS_HNTCH_FREQ": 81, "INS_HNTCH_BW": 40.5}


def _result(side: str, seed: int, scenario: str = "V2", **metrics) -> RunResult:
    spec = RunSpec(scenario=scenario, run_index=seed - 1, seed=seed, duration_s=40.0,
                   log_path="/nonexistent.mcap", variant=side, fc=nc.FC_OF_SIDE[side],
                   params=tuple(NOTCH.items()))
    return RunResult(spec=spec, metrics=metrics)


def _fly(work, seeds, ours_pp=4.0, theirs_pp=6.0):
    """Runs of one part: ours lower p-p on every seed; ArduCopter has no filtered gyro."""
    out = []
    for s in seeds:
        out.append(_result("ours", s, pwm_pp_us=ours_pp + s, gyro_noise_dps=0.02,
                           motor_noise_us=0.3, att_rms_deg=0.4, att_p95_deg=0.6, sat_pct=0.0,
                           gyro_in_noise_dps=20.0))
        for side in ("ardupilot", "ardupilot_ref"):
            out.append(_result(side, s, pwm_pp_us=theirs_pp + s, gyro_noise_dps=float("nan"),
                               motor_noise_us=0.3, att_rms_deg=0.3, att_p95_deg=0.5,
                               sat_pct=0.0, gyro_in_noise_dps=24.0))
    return nc.merge_runs(work, out)


def test_parts_flown_apart_are_merged_by_seed_and_judged_once(tmp_path):
    _fly(tmp_path, range(1, 6))
    rows = _fly(tmp_path, range(4, 11))            # seeds 4, 5 flown again: replaced
    assert len(rows) == 30
    assert sorted({r["seed"] for r in rows}) == list(range(1, 11))
    judged = nc.compare(nc.load_runs(tmp_path))
    pp = judged["V2"]["ardupilot"]["pwm_pp_us"]
    assert pp["n"] == 10 and pp["verdict"] == "at_or_below" and pp["median_diff"] == -2.0
    assert judged["V2"]["ardupilot_ref"]["att_rms_deg"]["text"] == "loses by 0.100 deg"
    assert judged["V2"]["ardupilot"]["gyro_noise_dps"]["verdict"] == "no_pairs"


def test_the_page_says_which_targets_are_met_and_by_how_much_ours_loses(tmp_path):
    rows = _fly(tmp_path, range(1, 11))
    page = notch_page.render(rows, "python -m silbridge.tools.docs.notch_page", "now")
    assert "seeds 1, 2, 3, 4, 5, 6, 7, 8, 9, 10" in page
    assert "- V2, hover PWM p-p against ArduCopter: met (at or below)." in page
    assert "gyro noise after filtering against ArduCopter: not measurable" in page
    assert "(ours: median 0.020 deg/s)" in page
    assert "| attitude RMS (deg) | 0.400 | 0.300 | 0.100 [0.100, 0.100] | 10 | loses by " \
           "0.100 deg |" in page
    assert "| gyro noise after filtering (deg/s) | 0.020 | n/a | n/a | 0 | not compared |" \
        in page
    assert "- attitude RMS against ArduCopter: ours loses by 0.100 deg." in page
    worse = _fly(tmp_path / "b", range(1, 11), ours_pp=9.0)
    page = notch_page.render(worse, "cmd", "now")
    assert "hover PWM p-p against ArduCopter: **not met: ours loses by 3.0 us**" in page


def test_a_page_without_runs_says_how_to_fly_them(tmp_path, capsys):
    assert notch_page.main(["--work", str(tmp_path), "--out", str(tmp_path / "p.md")]) == 2
    assert "fly the runs first (--run)" in capsys.readouterr().err
    assert notch_page.main(["--run", "--seeds", "5-2", "--work", str(tmp_path),
                            "--arducopter", "/bin/true", "--out", str(tmp_path / "p.md")]) == 2


def test_the_fft_sides_follow_their_fft_with_the_tuned_width():
    tuned = {**NOTCH, "INS_GYRO_FILTER": 20, "INS_HNTCH_HMNCS": 3}
    sides = nc.side_params(tuned, expo=0.65)
    ours = sides["ours_fft"]
    assert ours["INS_HNTCH_MODE"] == 4 and ours["FFT_ENABLE"] == 1 and ours["INS_HNTCH_REF"] == 1
    assert ours["INS_HNTCH_FREQ"] == ours["FFT_MINHZ"] == nc.FFT_MINHZ_HZ   # the notch's floor
    assert ours["INS_HNTCH_BW"] == 40.5 and ours["INS_HNTCH_HMNCS"] == 3
    px4 = sides["px4_fft"]
    assert px4["IMU_GYRO_DNF_EN"] == 2 and px4["IMU_GYRO_FFT_EN"] == 1   # bit 1: the FFT's
    assert px4["IMU_GYRO_DNF_BW"] == 30.0                 # 40.5 Hz is past PX4's range
    assert px4["IMU_GYRO_FFT_MAX"] < 125                  # below its 250 Hz gyro's Nyquist
    assert px4["IMU_GYRO_CUTOFF"] == 20.0 and px4["IMU_GYRO_DNF_MIN"] == nc.FFT_MINHZ_HZ
    assert sides["px4_off"] == {**px4, "IMU_GYRO_DNF_EN": 0}   # the same PX4, no notch


def test_px4_is_paired_with_ours_on_our_fft_and_only_where_both_flew(tmp_path):
    out = []
    for s in range(1, 6):
        out.append(_result("ours_fft", s, pwm_pp_us=5.0 + s, gyro_noise_dps=0.03,
                           motor_noise_us=0.4, att_rms_deg=0.4, att_p95_deg=0.6,
                           sat_pct=0.0, gyro_in_noise_dps=20.0))
        out.append(_result("px4_fft", s, pwm_pp_us=9.0 + s, gyro_noise_dps=float("nan"),
                           motor_noise_us=0.2, att_rms_deg=0.4, att_p95_deg=0.6,
                           sat_pct=0.0, gyro_in_noise_dps=21.0))
    out += [_result("px4_off", s, pwm_pp_us=11.0 + s, motor_noise_us=0.5) for s in range(1, 6)]
    nc.merge_runs(tmp_path, out)
    _fly(tmp_path, range(1, 6))                   # ours and ArduCopter too, same seeds
    rows = nc.load_runs(tmp_path)
    judged = nc.compare(rows)
    assert set(judged["V2"]) == {"ardupilot", "ardupilot_ref", "px4_fft", "px4_off"}
    assert judged["V2"]["px4_off"]["pwm_pp_us"]["median_diff"] == -2.0   # PX4 notch - none
    pp = judged["V2"]["px4_fft"]["pwm_pp_us"]
    assert pp["n"] == 5 and pp["median_diff"] == -4.0        # ours_fft - px4, not ours - px4
    page = notch_page.render(rows, "cmd", "now")
    assert "# Our harmonic notch against ArduCopter's and PX4's" in page
    assert "**Ours, notch on our FFT against PX4, notch on its FFT, paired by seed**" in page
    assert "- V2, hover PWM p-p against PX4, notch on its FFT: met (at or below)." in page
    assert "not measurable: PX4's filtered gyro does not reach silbridge " \
           "(ours: median 0.030 deg/s)" in page
    assert "folds back to ~88 Hz" in page
    assert "**PX4, notch on its FFT against PX4, no notch, paired by seed**" in page
    assert "against PX4, no notch:" not in page      # not a target of ours
