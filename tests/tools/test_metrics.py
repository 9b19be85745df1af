"""Metrics on synthetic logs whose answers are known on paper (tools/logs/log_synth.py)."""

import math

import numpy as np
import pytest

from silbridge.tools.logs.log_synth import quat_from_euler, synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter, read_log
from silbridge.tools.benchmark.metrics import Windows, compute_metrics, roll_pitch_from_quat

# A 12 s run; the analysis window holds whole periods of every sine below.
WIN = Windows(warmup=(0, 1), transient=(1, 2), analysis=(2, 12), yaw=(8, 12))


def _metrics(tmp_path, windows=WIN, **kw):
    run = synthetic_run(kw.pop("duration_s", 12.0), **kw)
    path = tmp_path / "m.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    return compute_metrics(read_log(path), windows)


def test_sine_gives_known_rms_p95_and_peak_to_peak(tmp_path):
    m = _metrics(tmp_path, roll_cmd_deg=5.0, roll_err_amp_deg=3.0, roll_err_hz=0.5,
                 pwm_amp_us=25.0, pwm_sine_hz=1.0)
    # e = 3 sin(...) deg: RMS = 3/sqrt(2); P95 of |sin| = sin(0.95 pi/2); max = 3.
    assert m["att_rms_deg"] == pytest.approx(3.0 / math.sqrt(2.0), rel=2e-3)
    assert m["att_p95_deg"] == pytest.approx(3.0 * math.sin(0.95 * math.pi / 2), rel=2e-3)
    assert m["att_max_deg"] == pytest.approx(3.0, rel=1e-4)
    assert m["att_rms_pitch_deg"] == pytest.approx(0.0, abs=1e-4)
    # PWM 1500 + 25 sin: the 400 Hz ticks hit both peaks, so p-p = 50 us exactly.
    assert m["pwm_pp_us"] == pytest.approx(50.0)
    assert m["pwm_pp_max_us"] == pytest.approx(50.0)
    assert m["sat_pct"] == 0.0
    assert m["window_note"] == ""


def test_ramp_gives_known_saturation_share(tmp_path):
    # Every motor ramps 1000 -> 2000 us over the run. PWM is published in whole
    # microseconds, so |u| >= 0.99 <=> pwm <= 1005 or >= 1995, i.e. ramp values
    # in [1000, 1005.5) or [1994.5, 2000]: 11 us of the 1000 us ramp = 1.1 %.
    m = _metrics(tmp_path, pwm_ramp=True, windows=Windows(analysis=(0, 12), yaw=(0, 12)))
    assert m["sat_pct"] == pytest.approx(1.1, abs=0.03)
    assert m["pwm_pp_us"] == pytest.approx(999.0, abs=1.0)


def test_yaw_rate_mixer_inputs_latency_and_jitter(tmp_path):
    m = _metrics(tmp_path, yaw_rate_rad_s=-0.03, cp_us=0.77, cr_us=-0.25, cy_us=2.0,
                 sensor_latency_us=20.0, end_to_end_us=80.0, period_jitter_us=4.0)
    assert m["yaw_rate_rad_s"] == pytest.approx(-0.03, rel=1e-6)
    assert m["yaw_rate_abs_rad_s"] == pytest.approx(0.03, rel=1e-6)
    assert (m["cp_us"], m["cr_us"], m["cy_us"]) == pytest.approx((0.77, -0.25, 2.0), rel=1e-6)
    assert m["latency_ms"] == pytest.approx(0.080) and m["latency_p99_ms"] == pytest.approx(0.080)
    assert m["sensor_latency_ms"] == pytest.approx(0.020)
    # period = 10 us + 4 us sin(2 pi k / 97): median 10 us, p99 |dev| ~ 4 us.
    assert m["loop_period_ms"] == pytest.approx(0.010, abs=1e-5)
    assert m["jitter_ms"] == pytest.approx(0.004, rel=0.01)
    assert m["jitter_p50_ms"] == pytest.approx(0.004 * math.sin(math.pi / 4), rel=0.05)


def test_short_log_uses_what_exists_and_says_so(tmp_path):
    m = _metrics(tmp_path, duration_s=6.0, roll_err_amp_deg=1.0, roll_err_hz=0.5)
    # Defaults ask for 30-120 s; the 6 s log has only warm-up: the whole log is used.
    m = compute_metrics(read_log(tmp_path / "m.mcap"))
    assert (m["analysis_start_s"], m["analysis_end_s"]) == (0.0, 6.0)
    assert "before the analysis window 30-120 s" in m["window_note"]
    assert "yaw rate over the analysis window" in m["window_note"]
    assert m["att_rms_deg"] == pytest.approx(1.0 / math.sqrt(2.0), rel=5e-3)
    # A window running past the end is cut to the log.
    m = compute_metrics(read_log(tmp_path / "m.mcap"), Windows(analysis=(2, 8), yaw=(4, 8)))
    assert m["analysis_end_s"] == 6.0 and "cut to 2-6.000 s" in m["window_note"]


def test_missing_channels_give_nan(tmp_path):
    run = synthetic_run(3.0)
    path = tmp_path / "pwm_only.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        w.write("/pwm", run.channels["/pwm"])
    m = compute_metrics(read_log(path), Windows(analysis=(0, 3), yaw=(0, 3)))
    assert m["pwm_pp_us"] == pytest.approx(40.0)
    assert math.isnan(m["att_rms_deg"]) and math.isnan(m["latency_ms"])


def test_quaternion_to_roll_pitch_matches_the_construction():
    rng = np.random.default_rng(4)
    roll, pitch, yaw = rng.uniform(-1.2, 1.2, (3, 500))
    r, p = roll_pitch_from_quat(quat_from_euler(roll, pitch, yaw))
    np.testing.assert_allclose(r, roll, atol=1e-12)
    np.testing.assert_allclose(p, pitch, atol=1e-12)


def test_bad_window_is_refused():
    with pytest.raises(ValueError, match="analysis"):
        Windows(analysis=(30, 20))
