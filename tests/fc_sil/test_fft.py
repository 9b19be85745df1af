"""fc_fft: the in-flight gyro FFT (ArduCopter 4.6's FFT_*), block level.

- The radix-2 transform equals numpy.fft.fft of the same Hann-windowed samples.
- A harmonic series (f0, 2 f0 strongest, 3 f0, noise) is found within one bin on every
  tracked slot; the harmonic fit recognises 2 f0 as f0's harmonic, and the notch is handed f0.
- No peak above FFT_SNR_REF: unhealthy, and the notch gets ArduPilot's throttle estimate.
- FFT_ENABLE 0: nothing runs and the notch gets FFT_MINHZ.
- Hover learning moves FFT_FREQ_HOVER and FFT_THR_REF as AP_GyroFFT::update_freq_hover.
"""

import numpy as np
import pytest

from fft_block import COUNTS_PER_RAD_S, GyroFft, lib, tones

FS = 1000.0


def _hann(n):
    """ArduPilot's window (DSP.cpp: periodic in N - 1)."""
    return 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / (n - 1))


@pytest.mark.parametrize("n", [32, 64, 256, 512])
def test_transform_matches_numpy_fft(n):
    rng = np.random.default_rng(n)
    x = rng.standard_normal((n, 3)) * 0.3
    fft = GyroFft(FS, window_size=n, window_overlap=0.0)
    fft.push(x)
    while fft.f.frames_done < 1:          # the first frame is roll's
        lib.fc_fft_step(fft.f)
    want = np.fft.fft(x[:, 0].astype(np.float32).astype(np.float64) * COUNTS_PER_RAD_S * _hann(n))
    got = fft.spectrum_bins()
    assert np.max(np.abs(got - want)) < 2e-6 * np.max(np.abs(want))


def _calibrated(fft, seconds=1.0, noise=0.002):
    """Still vehicle first: the noise reference is learned (as at boot)."""
    fft.feed(tones(FS, seconds, [], noise=noise, seed=7))
    assert fft.f.needs_calibration == 0


SERIES_F0 = 93.7
SERIES = [(SERIES_F0, 0.05, 0.0), (2 * SERIES_F0, 0.10, 0.4), (3 * SERIES_F0, 0.04, 1.1)]


@pytest.mark.parametrize("n,frames", [(32, 0), (256, 0), (256, 4)])
def test_harmonic_series_found_within_one_bin_and_fitted(n, frames):
    fft = GyroFft(FS, window_size=n, num_frames=frames, min_hz=40.0, max_hz=450.0)
    _calibrated(fft)
    fft.feed(tones(FS, 3.0, SERIES, noise=0.002))
    bin_hz = fft.f.bin_hz
    for axis in (0, 1):
        found = sorted(fft.track_hz(axis, s) for s in range(3))
        want = [hz for hz, _, _ in SERIES]
        if n == 32:   # 31 Hz bins: 3 f0 sits two bins from 2 f0, only two peaks are resolved
            found, want = found[:2], want[:2]
        assert np.all(np.abs(np.array(found) - want) <= bin_hz), (axis, found)
        assert fft.f.harmonic_fit[axis] < fft.cfg.hmnc_fit_pct   # 2 f0 is f0's harmonic
    assert abs(fft.center_hz() - SERIES_F0) <= bin_hz
    assert abs(fft.notch_freqs()[0] - SERIES_F0) <= bin_hz


def test_single_tone_is_its_own_fundamental():
    fft = GyroFft(FS, window_size=256, min_hz=40.0, max_hz=450.0)
    _calibrated(fft)
    fft.feed(tones(FS, 2.0, [(151.3, 0.08, 0.0)], noise=0.002))
    assert fft.f.harmonic_fit[0] == 100.0            # nothing below it to fit
    assert abs(fft.center_hz() - 151.3) < 0.5 * fft.f.bin_hz


def test_noise_only_is_unhealthy_and_falls_back_to_throttle():
    fft = GyroFft(FS, window_size=64)
    _calibrated(fft)
    fft.feed(tones(FS, 2.0, [], noise=0.002, seed=9))
    thr = 0.7
    want = 80.0 * np.sqrt(thr / 0.35)                # FFT_MINHZ * sqrt(throttle / FFT_THR_REF)
    assert fft.center_hz(thr) == pytest.approx(want, rel=1e-5)
    assert fft.notch_freqs(thr) == pytest.approx([want], rel=1e-5)


def test_disabled_does_nothing_and_reports_minhz():
    fft = GyroFft(FS, enable=False)
    units = fft.feed(tones(FS, 0.5, [(120.0, 0.1, 0.0)]))
    assert units.max() == 0 and fft.f.frames_done == 0
    assert fft.center_hz() == 80.0 and fft.notch_freqs() == [80.0]


def test_hover_learning_follows_the_tracked_frequency():
    fft = GyroFft(FS, window_size=256, min_hz=40.0, max_hz=300.0)
    _calibrated(fft)
    fft.feed(tones(FS, 2.0, [(120.0, 0.08, 0.0)], noise=0.002))
    for _ in range(10_000):                          # 100 s at 100 Hz: ten time constants
        lib.fc_fft_update_freq_hover(fft.f, 0.01, 0.4)
    assert fft.f.freq_hover_hz == pytest.approx(fft.center_hz(), rel=1e-3)
    assert fft.f.thr_ref == pytest.approx(0.4 * (40.0 / fft.f.freq_hover_hz) ** 2, rel=1e-3)
    assert fft.f.learned


def test_core_runs_the_fft_from_its_parameters():
    """FFT_ENABLE through the parameter table: pre-arm says "calibrating" until the noise
    reference is learned, the IMU step feeds the FFT, FTN rows have the logged layout, and
    MODE 4 reads the tracked line."""
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.tools.logs.ftn_log import FTN1_DTYPE, FTN2_DTYPE

    core = FlightCore()
    assert core.fft_notch_freqs(0.3) == (80.0,)      # off: FFT_MINHZ, as ArduPilot
    assert not core.fft_calibrating()
    core.set_param("FFT_ENABLE", 1)
    core.set_param("FFT_WINDOW_SIZE", 256)
    assert core.fft_calibrating()
    rows = np.concatenate([tones(FS, 2.0, [], noise=0.002),
                           tones(FS, 2.0, [(123.0, 0.08, 0.0)], noise=0.002, seed=2)])
    for i, g in enumerate(rows):
        core.step_imu((i + 1) * 1_000_000, (0.0, 0.0, -9.80665), g)
        if i == 1500:
            assert not core.fft_calibrating()
    assert core.fft_notch_freqs(0.3)[0] == pytest.approx(123.0, abs=1.0)
    ftn1, ftn2 = core.fft_ftn()
    assert ftn1.dtype == FTN1_DTYPE and len(ftn1) == 1 and ftn2.dtype == FTN2_DTYPE
    assert ftn1["pk_avg_hz"][0] == pytest.approx(123.0, abs=1.0) and ftn1["health"][0] == 1
    assert ftn2["id"].tolist() == [0, 1, 2]
