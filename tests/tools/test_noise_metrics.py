"""Table 1's noise metrics (tools/benchmark/noise.py): known tones give their known RMS,
what lies below the band does not count, a held output reads as itself, and a real flight
in a vibrating world produces them all, with the filtered gyro quieter than its input."""

import math

import numpy as np
import pytest

from silbridge.tools.benchmark.metrics import Windows, compute_metrics
from silbridge.tools.benchmark.noise import KEYS, band_noise, noise_metrics, vector_rms
from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter, read_log


def _tone(rate_hz, f_hz, amp, seconds=10.0, phase=0.3):
    t = np.arange(int(seconds * rate_hz)) / rate_hz
    return amp * np.sin(2 * np.pi * f_hz * t + phase)


@pytest.mark.parametrize("f_hz", [25.0, 63.3, 150.0, 190.0])
def test_a_tone_in_band_reads_its_rms(f_hz):
    x = _tone(400.0, f_hz, 3.0) + _tone(400.0, 2.0, 40.0)     # + a big slow control motion
    assert band_noise(x, 400.0)[0] == pytest.approx(3.0 / math.sqrt(2.0), rel=0.01)


def test_below_the_band_does_not_count_and_axes_combine_in_quadrature():
    x = np.stack([_tone(400.0, 5.0, 10.0), _tone(400.0, 80.0, 3.0), _tone(400.0, 120.0, 4.0)],
                 axis=1)
    axes = band_noise(x, 400.0)
    assert axes[0] < 0.01
    assert axes[1:] == pytest.approx([3.0 / math.sqrt(2), 4.0 / math.sqrt(2)], rel=0.01)
    assert vector_rms(axes) == pytest.approx(5.0 / math.sqrt(2), rel=0.01)


def test_a_400_hz_output_held_at_1_khz_reads_as_itself():
    # ArduCopter's case: its 400 Hz PWM logged per 1 kHz physics step (held 2-3 steps).
    out = _tone(400.0, 120.0, 25.0) + _tone(400.0, 1.0, 50.0)
    t_log = np.arange(1, 10_001) / 1000.0
    held = out[np.clip(np.searchsorted(np.arange(len(out)) / 400.0, t_log, "right") - 1, 0, None)]
    assert band_noise(held, 1000.0)[0] == pytest.approx(band_noise(out, 400.0)[0], rel=1e-3)


def test_too_short_or_too_slow_gives_nan():
    assert np.isnan(band_noise(np.zeros(50), 400.0)[0])        # 0.125 s: no usable segment
    assert np.isnan(band_noise(np.zeros(400), 30.0)[0])        # Nyquist below 20 Hz


def _synthetic_log(tmp_path):
    """A synthetic run whose FC status and PWM carry known tones (log_synth: 400 Hz status and
    PWM, 1 kHz IMU with white gyro noise of 0.002 rad/s per axis)."""
    run = synthetic_run(12.0, pwm_amp_us=25.0, pwm_sine_hz=50.0)
    st = run.channels["/fc/status"]
    t = st["sim_ns"] * 1e-9
    st["rate_frd_rad_s"][:, 0] = np.radians(2.0) * np.sin(2 * np.pi * 70.0 * t)
    st["rate_frd_rad_s"][:, 1] = np.radians(1.0) * np.sin(2 * np.pi * 3.0 * t)   # below band
    st["rate_frd_rad_s"][:, 2] = 0.01                                           # constant
    st["pid_d"][:, 0] = 6.0 * np.sin(2 * np.pi * 45.0 * t)
    st["pid_d"][:, 1] = 8.0 * np.sin(2 * np.pi * 110.0 * t)
    path = tmp_path / "noise.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    return read_log(path)


def test_noise_metrics_of_a_log_with_known_signals(tmp_path):
    m = noise_metrics(_synthetic_log(tmp_path), (2.0, 12.0))
    assert set(m) == set(KEYS)
    assert m["gyro_noise_roll_dps"] == pytest.approx(2.0 / math.sqrt(2), rel=0.01)
    assert m["gyro_noise_pitch_dps"] < 0.01 and m["gyro_noise_yaw_dps"] < 1e-6
    assert m["gyro_noise_dps"] == pytest.approx(2.0 / math.sqrt(2), rel=0.01)
    assert m["dterm_noise_us"] == pytest.approx(10.0 / math.sqrt(2), rel=0.01)
    # Each motor: 1500 + 25 sin(2 pi 50 t + phase), rounded to whole us (+0.29 us RMS at most).
    assert m["motor_noise_us"] == pytest.approx(25.0 / math.sqrt(2), rel=0.01)
    assert m["motor_noise_max_us"] == pytest.approx(25.0 / math.sqrt(2), rel=0.01)
    # White gyro noise, 0.002 rad/s per axis at 1 kHz: the share 20..500 Hz of its power.
    white = math.degrees(0.002) * math.sqrt(3 * 480.0 / 500.0)
    assert m["gyro_in_noise_dps"] == pytest.approx(white, rel=0.03)


def test_a_foreign_autopilots_log_has_no_filtered_gyro_but_the_rest(tmp_path):
    log = _synthetic_log(tmp_path)
    # ArduCopter's and PX4's /fc/status has none of our FC's fields (log_sink.AP_STATUS_DTYPE).
    log.channels["/fc/status"] = log.channels["/fc/status"][["sim_ns", "att_target_rad"]]
    m = noise_metrics(log, (2.0, 12.0))
    assert math.isnan(m["gyro_noise_dps"]) and math.isnan(m["dterm_noise_us"])
    assert m["motor_noise_us"] > 0 and m["gyro_in_noise_dps"] > 0


def test_a_real_vibrating_flight_produces_them(tmp_path):
    """V2 (a vibrating vehicle, docs/explanation/vibrating-world.md) flown by our FC as a
    benchmark run flies it: every noise metric is a finite positive number, and the FC's
    filters leave much less in the gyro the rate loop uses than the IMU gave it."""
    from silbridge.tools.benchmark.campaign import RunSpec, run_one

    spec = RunSpec(scenario="V2", run_index=0, seed=1, duration_s=12.0,
                   log_path=str(tmp_path / "v2.mcap"),
                   windows=((0.0, 4.0), (4.0, 6.0), (6.0, 12.0), (9.0, 12.0)))
    r = run_one(spec)
    assert r.problems == []
    m = r.metrics
    for key in KEYS:
        assert math.isfinite(m[key]) and m[key] > 0, key
    assert m["gyro_noise_dps"] < 0.25 * m["gyro_in_noise_dps"]
    # The same numbers from the log as `silbridge analyze` reads it.
    again = compute_metrics(read_log(spec.log_path), Windows(*spec.windows))
    assert again["motor_noise_us"] == m["motor_noise_us"]
