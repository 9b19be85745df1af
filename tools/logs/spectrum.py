"""Spectra of evenly sampled signals: Welch's average and the spectrogram, in numpy alone.

Why here and not scipy.signal: scipy is only in the `tune` extra, and the light install
(`fly`, `bench`, `analyze`) must read a log's vibration too. The tests hold these against
`scipy.signal.welch` and `scipy.signal.spectrogram` (tests/tools/test_spectrum.py).

Method (the same as scipy's defaults for `window="hann"`, `detrend="constant"`):
- the signal is cut into segments of `segment_n` samples, each `step_n` after the previous
  (half a segment: 50 % overlap); a segment's mean is removed, then it is multiplied by a
  periodic Hann window w and transformed;
- the frequency resolution (bin spacing) is rate / segment_n; a Hann window spreads a pure
  tone over a main lobe of +-2 bins, and its equivalent noise bandwidth is 1.5 bins;
- `psd` is the one-sided power spectral density [unit^2/Hz]: 2 |X|^2 / (rate sum w^2)
  (DC and Nyquist not doubled), averaged over segments;
- `amp` is the amplitude of the sinusoid that would give the averaged power in that bin
  [unit]: 2 sqrt(mean |X|^2) / sum w. A tone sitting on a bin reads its amplitude; one
  between two bins reads up to 15 % low (the Hann scalloping loss), which the peak finder
  (tools/logs/spectrum_peaks.py) corrects.
"""

from __future__ import annotations

import dataclasses

import numpy as np

OVERLAP = 0.5           # Welch's own choice for a Hann window: each sample weighs about equally


@dataclasses.dataclass(frozen=True)
class Spectrum:
    """Welch's average of one signal's segments; columns are the signal's axes."""

    freq_hz: np.ndarray     # (n_bins,) bin centres
    psd: np.ndarray         # (n_bins, n_axes) one-sided PSD [unit^2/Hz]
    amp: np.ndarray         # (n_bins, n_axes) equivalent sinusoid amplitude [unit]
    rate_hz: float          # sample rate of the signal
    segment_n: int          # samples per segment
    segments: int           # segments averaged

    @property
    def resolution_hz(self) -> float:
        """Bin spacing: rate / segment length."""
        return self.rate_hz / self.segment_n


@dataclasses.dataclass(frozen=True)
class Spectrogram:
    """One spectrum per segment: power over time."""

    t_s: np.ndarray         # (n_seg,) centre of each segment, in the signal's time
    freq_hz: np.ndarray     # (n_bins,)
    amp: np.ndarray         # (n_seg, n_bins, n_axes) equivalent sinusoid amplitude [unit]
    resolution_hz: float


def hann(n: int) -> np.ndarray:
    """The periodic Hann window (scipy.signal.get_window("hann", n)): its n-point DFT
    has exactly three non-zero bins, so the scalloping correction is exact."""
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def segment_power(x: np.ndarray, segment_n: int, step_n: int) -> tuple[np.ndarray, np.ndarray]:
    """|X|^2 of each windowed, mean-removed segment: ((n_seg, n_bins, n_axes), start indices).

    x: (n_samples, n_axes) or (n_samples,). Raises ValueError when x is shorter than one
    segment (the caller says which window and segment length to change).
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if segment_n < 4 or len(x) < segment_n:
        raise ValueError(f"{len(x)} samples, fewer than one segment of {segment_n}")
    step_n = max(int(step_n), 1)
    starts = np.arange(0, len(x) - segment_n + 1, step_n)
    # Segments as a strided view (n_seg, n_axes, segment_n), each one contiguous once its
    # mean is taken off: no gathered copy, and the FFT runs on contiguous rows (a campaign
    # run's metrics took 13 ms a spectrum with the copy, 9 without; the same powers).
    view = np.lib.stride_tricks.sliding_window_view(x, segment_n, axis=0)[::step_n]
    seg = view - view.mean(axis=2, keepdims=True)
    seg *= hann(segment_n)
    spec = np.fft.rfft(seg, axis=2)
    return (spec.real ** 2 + spec.imag ** 2).transpose(0, 2, 1), starts


def _amplitude(power: np.ndarray, segment_n: int) -> np.ndarray:
    return 2.0 * np.sqrt(power) / hann(segment_n).sum()


def welch(x: np.ndarray, rate_hz: float, segment_n: int) -> Spectrum:
    """Welch's average over segments of segment_n samples, 50 % overlap, Hann window."""
    power, starts = segment_power(x, segment_n, int(segment_n * (1.0 - OVERLAP)))
    mean = power.mean(axis=0)                           # (n_bins, n_axes)
    w = hann(segment_n)
    psd = mean / (rate_hz * (w * w).sum())
    psd[1:] *= 2.0                                      # one-sided: fold negative frequencies
    if segment_n % 2 == 0:
        psd[-1] /= 2.0                                  # ... except the Nyquist bin
    return Spectrum(freq_hz=np.fft.rfftfreq(segment_n, 1.0 / rate_hz), psd=psd,
                    amp=_amplitude(mean, segment_n), rate_hz=float(rate_hz),
                    segment_n=int(segment_n), segments=len(starts))


def spectrogram(x: np.ndarray, rate_hz: float, segment_n: int,
                t0_s: float = 0.0) -> Spectrogram:
    """Amplitude spectrum of each segment (50 % overlap, Hann); t_s: segment centres,
    counted from t0_s, the time of x's first sample."""
    power, starts = segment_power(x, segment_n, int(segment_n * (1.0 - OVERLAP)))
    t_s = t0_s + (starts + 0.5 * segment_n) / rate_hz      # as scipy: the middle of the span
    return Spectrogram(t_s=t_s, freq_hz=np.fft.rfftfreq(segment_n, 1.0 / rate_hz),
                       amp=_amplitude(power, segment_n), resolution_hz=rate_hz / segment_n)


def band_rms(sp: Spectrum, lo_hz: float, hi_hz: float | None = None) -> np.ndarray:
    """RMS of each axis within [lo_hz, hi_hz] (default: up to Nyquist), from the PSD."""
    f = sp.freq_hz
    keep = (f >= lo_hz) & (f <= (hi_hz if hi_hz is not None else f[-1]))
    return np.sqrt(sp.psd[keep].sum(axis=0) * sp.resolution_hz)
