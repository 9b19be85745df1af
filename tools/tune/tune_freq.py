"""Frequency responses from a sweep, and stability margins of a loop.

Estimation: Welch cross-spectra (scipy.signal.csd / welch, Hann windows, 50 %
overlap) against the injected sweep d as the instrument. A ratio of two
responses to d, H_dy / H_dx, is the transfer x -> y even inside a closed loop
(noise and feedback paths that do not start at d cancel), which is why every
estimate here divides two cross-spectra with d rather than using x's own
spectrum. Coherence: the smaller of d's coherence with x and with y, i.e. how
much of both signals the sweep explains.

Margins from a frequency response L (open loop, negative feedback 1 + L):
crossover where |L| falls through 1 (first crossing, log-frequency
interpolation), phase margin 180 + arg L there, phase crossover where the
unwrapped phase falls through -180 deg, gain margin -|L| in dB there, delay
margin PM / omega_c. A crossing outside the frequencies given is reported as
None (the sweep did not reach it), never guessed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal


@dataclass
class Frf:
    f_hz: np.ndarray
    h: np.ndarray            # complex response
    coherence: np.ndarray    # 0..1

    def band(self, coh_min: float) -> np.ndarray:
        return self.coherence >= coh_min

    def mag_db(self) -> np.ndarray:
        return 20.0 * np.log10(np.abs(self.h))

    def phase_deg(self) -> np.ndarray:
        return np.degrees(np.unwrap(np.angle(self.h)))

    def select(self, mask) -> "Frf":
        return Frf(self.f_hz[mask], self.h[mask], self.coherence[mask])


def _nperseg(n: int, fs: float, f_lo: float) -> int:
    """Segments long enough for about 4 periods of the lowest frequency of interest."""
    want = int(2 ** math.ceil(math.log2(max(64.0, 4.0 * fs / max(f_lo, 1e-3)))))
    return max(64, min(want, n // 4 if n >= 256 else n))


class SweepSpectra:
    """Cross-spectra of every signal with the sweep d, computed once each."""

    def __init__(self, d, fs: float, f_lo: float, nperseg: int | None = None):
        self.d = np.asarray(d, dtype=float)
        self.fs = fs
        self.nperseg = nperseg or _nperseg(len(self.d), fs, f_lo)
        self.f, self.pdd = signal.welch(self.d, fs=fs, nperseg=self.nperseg)
        self._cache: dict[int, tuple] = {}

    def _with(self, x) -> tuple[np.ndarray, np.ndarray]:
        key = id(x)
        if key not in self._cache:
            x = np.asarray(x, dtype=float)
            _, pdx = signal.csd(self.d, x, fs=self.fs, nperseg=self.nperseg)
            _, pxx = signal.welch(x, fs=self.fs, nperseg=self.nperseg)
            coh = np.abs(pdx) ** 2 / np.maximum(self.pdd * pxx, 1e-300)
            self._cache[key] = (pdx, np.clip(coh, 0.0, 1.0), x)
        return self._cache[key][:2]

    def response(self, x) -> Frf:
        """d -> x."""
        pdx, coh = self._with(x)
        return Frf(self.f, pdx / np.maximum(self.pdd, 1e-300), coh)

    def transfer(self, x, y) -> Frf:
        """x -> y, with d as the instrument."""
        pdx, cx = self._with(x)
        pdy, cy = self._with(y)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = pdy / pdx
        return Frf(self.f, h, np.minimum(cx, cy))


def _log_interp(f0, f1, v0, v1, v):
    """Frequency at which a quantity linear in log f crosses v between two points."""
    if v1 == v0:
        return f0
    a = (v - v0) / (v1 - v0)
    return float(math.exp(math.log(f0) + a * (math.log(f1) - math.log(f0))))


def _wrap180(x):
    return (np.asarray(x) + 180.0) % 360.0 - 180.0


def margins(f_hz, loop_h) -> dict:
    """Gain/phase/delay margins of the loop response loop_h at f_hz (ascending, > 0).

    Phase margin: 180 + arg L at the gain crossover, wrapped to (-180, 180].
    Gain margin: at the first frequency above the gain crossover where the phase
    falls through -180 (mod 360), the classical margin of a loop that is
    stable at low frequency even if its phase starts near -180 (integrators)."""
    f = np.asarray(f_hz, dtype=float)
    h = np.asarray(loop_h, dtype=complex)
    ok = np.isfinite(h) & (np.abs(h) > 0) & (f > 0)
    f, h = f[ok], h[ok]
    out = {"crossover_hz": None, "phase_margin_deg": None, "delay_margin_ms": None,
           "phase_crossover_hz": None, "gain_margin_db": None}
    if len(f) < 2:
        return out
    mag = 20.0 * np.log10(np.abs(h))
    ph = np.degrees(np.unwrap(np.angle(h)))
    q = _wrap180(ph + 180.0)      # distance of the phase above -180 (mod 360)
    start = 0
    for i in range(len(f) - 1):
        if mag[i] >= 0.0 > mag[i + 1]:
            fc = _log_interp(f[i], f[i + 1], mag[i], mag[i + 1], 0.0)
            a = math.log(fc / f[i]) / math.log(f[i + 1] / f[i])
            pm = float(_wrap180(ph[i] + a * (ph[i + 1] - ph[i]) + 180.0))
            out.update(crossover_hz=fc, phase_margin_deg=pm,
                       delay_margin_ms=float(math.radians(pm) / (2 * math.pi * fc) * 1e3))
            start = i
            break
    for i in range(start, len(f) - 1):
        falls = q[i] > 0.0 >= q[i + 1] and (q[i] - q[i + 1]) < 180.0
        if falls and (out["crossover_hz"] is None or f[i + 1] >= out["crossover_hz"]):
            fp = _log_interp(f[i], f[i + 1], q[i], q[i + 1], 0.0)
            a = math.log(fp / f[i]) / math.log(f[i + 1] / f[i])
            out.update(phase_crossover_hz=fp, gain_margin_db=float(-(mag[i] + a * (mag[i + 1] - mag[i]))))
            break
    return out


def bandwidth_hz(f_hz, closed_h) -> float | None:
    """-3 dB bandwidth of a closed loop: first frequency where |T| falls below
    1/sqrt(2) of its low-frequency value (the first point given)."""
    f = np.asarray(f_hz, dtype=float)
    mag = 20.0 * np.log10(np.abs(np.asarray(closed_h)))
    ref = mag[0]
    for i in range(len(f) - 1):
        if mag[i] - ref >= -3.0 > mag[i + 1] - ref:
            return _log_interp(f[i], f[i + 1], mag[i] - ref, mag[i + 1] - ref, -3.0)
    return None


def smooth_band(frf: Frf, coh_min: float, f_lo: float, f_hi: float) -> Frf:
    """The part of frf inside [f_lo, f_hi] with coherence >= coh_min."""
    m = (frf.f_hz >= f_lo) & (frf.f_hz <= f_hi) & (frf.coherence >= coh_min) & np.isfinite(frf.h)
    return frf.select(m)
