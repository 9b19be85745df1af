"""Peaks of an amplitude spectrum, and which rotor harmonic each one sits at.

A peak is a bin that is the largest within +-SEPARATION_BINS bins and stands FLOOR_FACTOR
above the band's median (the noise floor), at or above a lowest frequency (below it the
vehicle's own motion lives, not vibration). The separation is the Hann window's reach:
its main lobe spans +-2 bins and its first sidelobes sit at +-2.5 and +-3.5 bins
(-31 dB), so a tone gives one peak, and two tones closer than 4 bins read as one.

Each peak's frequency and amplitude are refined between bins: a Hann main lobe is close
to a Gaussian in log amplitude, so a parabola through the log amplitudes of the peak bin
and its two neighbours places the tone to a few hundredths of a bin (Gasior and
Gonzalez, CERN-AB-2004-023), and the amplitude is divided by the window's response at
that offset, sinc(d) / (1 - d^2), removing the up-to-15 % scalloping loss.

Harmonics: with a rotor frequency f_rot, a peak at f is labelled k = round(f / f_rot) when
|f - k f_rot| <= max(resolution, k * spread): the bin spacing, or the rotor frequency's
own spread over the window (four motors at different speeds, throttle changes) times k.
"""

from __future__ import annotations

import dataclasses

import numpy as np

SEPARATION_BINS = 4     # the Hann main lobe and first sidelobes (see above)
FLOOR_FACTOR = 4.0      # 12 dB above the median of the band: clear of the noise's own scatter
MIN_HZ = 20.0           # below: the vehicle's motion (attitude loop bandwidth ~ 10 Hz);
#                         above: rotor harmonics (10-inch props idle near 30 Hz)
MAX_HARMONIC = 8        # beyond the 8th a match is a coincidence of a dense spectrum


@dataclasses.dataclass(frozen=True)
class Peak:
    freq_hz: float          # refined between bins
    amp: float              # equivalent sinusoid amplitude, scalloping corrected [unit]
    harmonic: int | None    # k when it sits at k x the rotor frequency, else None
    order: float | None     # freq / rotor frequency (None without rotor speed)


def refine(amp: np.ndarray, i: int) -> tuple[float, float]:
    """(offset in bins, amplitude correction factor) of the tone near bin i."""
    if i == 0 or i == len(amp) - 1:
        return 0.0, 1.0
    a, b, c = np.log(np.maximum(amp[i - 1:i + 2], 1e-300))
    den = a - 2.0 * b + c
    d = 0.0 if den >= 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))
    resp = np.sinc(d) / (1.0 - d * d)
    return d, 1.0 / resp


def find_peaks(freq_hz: np.ndarray, amp: np.ndarray, count: int, min_hz: float = MIN_HZ
               ) -> list[tuple[float, float]]:
    """The `count` largest peaks of one axis: [(freq_hz, amp)], largest first."""
    band = np.flatnonzero(freq_hz >= min_hz)
    if len(band) < 3:
        return []
    floor = float(np.median(amp[band]))
    padded = np.pad(amp, SEPARATION_BINS, constant_values=-np.inf)
    width = 2 * SEPARATION_BINS + 1
    local_max = np.lib.stride_tricks.sliding_window_view(padded, width).max(axis=1)
    cand = [i for i in band if amp[i] >= local_max[i] and amp[i] > FLOOR_FACTOR * floor]
    cand.sort(key=lambda i: -amp[i])
    df = freq_hz[1] - freq_hz[0]
    out = []
    for i in cand[:count]:
        d, gain = refine(amp, i)
        out.append((float(freq_hz[i] + d * df), float(amp[i] * gain)))
    return out


def harmonic_of(freq_hz: float, rotor_hz: float, resolution_hz: float,
                spread_hz: float = 0.0) -> int | None:
    """k when freq_hz is within max(resolution, k x spread) of k x rotor_hz, else None."""
    if not rotor_hz > 0:
        return None
    k = int(round(freq_hz / rotor_hz))
    if not 1 <= k <= MAX_HARMONIC:
        return None
    return k if abs(freq_hz - k * rotor_hz) <= max(resolution_hz, k * spread_hz) else None


def label_peaks(peaks: list[tuple[float, float]], rotor_hz: float | None,
                resolution_hz: float, spread_hz: float = 0.0) -> list[Peak]:
    """Peaks with their harmonic number and order (None without a rotor frequency)."""
    if rotor_hz is None or not rotor_hz > 0:
        return [Peak(f, a, None, None) for f, a in peaks]
    return [Peak(f, a, harmonic_of(f, rotor_hz, resolution_hz, spread_hz), f / rotor_hz)
            for f, a in peaks]
