"""The spectrum maths (tools/logs/spectrum.py, spectrum_peaks.py) against scipy.signal.

scipy is the oracle (the package itself uses numpy alone): Welch's PSD and the
spectrogram must equal scipy's for the same window, segment and overlap; a tone between
two bins is found at its frequency and amplitude; a peak is labelled with the rotor
harmonic it sits at, and with none when it sits between harmonics or without rotor speed.
"""

from __future__ import annotations

import numpy as np
import pytest

from silbridge.tools.logs.spectrum import band_rms, spectrogram, welch
from silbridge.tools.logs.spectrum_peaks import find_peaks, harmonic_of, label_peaks

signal = pytest.importorskip("scipy.signal")

RATE_HZ = 1000.0


def _tones(duration_s: float, tones, noise: float = 1e-3, seed: int = 3) -> np.ndarray:
    t = np.arange(int(duration_s * RATE_HZ)) / RATE_HZ
    x = np.random.default_rng(seed).normal(0.0, noise, (len(t), 2))
    for f, a, col in tones:
        x[:, col] += a * np.sin(2 * np.pi * f * t + 0.3)
    return x


def test_welch_equals_scipy():
    x = _tones(4.0, [(74.3, 0.2, 0), (148.6, 0.05, 1)]) + [0.5, -9.8]   # offsets removed
    sp = welch(x, RATE_HZ, 1000)
    f, psd = signal.welch(x, RATE_HZ, window="hann", nperseg=1000, axis=0)
    np.testing.assert_allclose(sp.freq_hz, f)
    np.testing.assert_allclose(sp.psd, psd, rtol=1e-9, atol=1e-15)
    assert sp.resolution_hz == 1.0 and sp.segments == 7
    # Parseval: the band RMS of a tone is its amplitude / sqrt 2.
    assert band_rms(sp, 20.0)[0] == pytest.approx(0.2 / 2 ** 0.5, rel=0.01)


def test_spectrogram_equals_scipy():
    x = _tones(2.0, [(100.0, 1.0, 0)])
    sg = spectrogram(x, RATE_HZ, 250, t0_s=5.0)
    f, t, sxx = signal.spectrogram(x, RATE_HZ, window="hann", nperseg=250, noverlap=125,
                                   axis=0, scaling="spectrum", mode="magnitude")
    np.testing.assert_allclose(sg.freq_hz, f)
    np.testing.assert_allclose(sg.t_s - 5.0, t, rtol=1e-12)
    # scipy's "magnitude" is |X| / sum w (a one-sided |X| would be doubled): ours is 2x that.
    np.testing.assert_allclose(sg.amp[:, :, 0], 2.0 * np.moveaxis(sxx[:, 0, :], -1, 0),
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("freq_hz", [74.0, 74.25, 74.5, 131.8])
def test_a_tone_between_bins_is_found_at_its_frequency_and_amplitude(freq_hz):
    x = _tones(8.0, [(freq_hz, 0.3, 0), (2 * freq_hz, 0.03, 0)])
    sp = welch(x, RATE_HZ, 1000)
    peaks = find_peaks(sp.freq_hz, sp.amp[:, 0], count=5)
    assert len(peaks) == 2                                  # no sidelobe counted as a peak
    (f1, a1), (f2, a2) = peaks
    assert f1 == pytest.approx(freq_hz, abs=0.05 * sp.resolution_hz)
    assert a1 == pytest.approx(0.3, rel=0.02)               # scalloping corrected
    assert f2 == pytest.approx(2 * freq_hz, abs=0.05 * sp.resolution_hz)
    assert a2 == pytest.approx(0.03, rel=0.02)


def test_no_peak_in_white_noise_and_none_below_the_band():
    x = _tones(8.0, [(8.0, 1.0, 0)], noise=0.01)             # 8 Hz: vehicle motion
    sp = welch(x, RATE_HZ, 1000)
    assert find_peaks(sp.freq_hz, sp.amp[:, 0], count=5) == []
    assert find_peaks(sp.freq_hz, sp.amp[:, 1], count=5) == []


def test_harmonic_labels():
    rotor = 74.3
    assert harmonic_of(74.9, rotor, resolution_hz=1.0) == 1
    assert harmonic_of(148.0, rotor, resolution_hz=1.0) == 2        # blade pass
    assert harmonic_of(223.5, rotor, resolution_hz=1.0) == 3
    assert harmonic_of(111.0, rotor, resolution_hz=1.0) is None     # between 1x and 2x
    assert harmonic_of(226.0, rotor, resolution_hz=1.0) is None     # 3x is 222.9
    assert harmonic_of(226.0, rotor, resolution_hz=1.0, spread_hz=1.2) == 3
    peaks = label_peaks([(148.0, 0.1), (111.0, 0.01)], rotor, 1.0)
    assert [p.harmonic for p in peaks] == [2, None]
    assert peaks[0].order == pytest.approx(148.0 / rotor)
    assert [p.harmonic for p in label_peaks([(148.0, 0.1)], None, 1.0)] == [None]
