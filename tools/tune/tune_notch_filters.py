"""The gyro filter chain's frequency response, as the FC core builds it: the harmonic
notch bank (INS_HNTCH_*, fc_sil/core/fc_notch.h) then the gyro low-pass
(INS_GYRO_FILTER, a pre-warped 2nd-order Butterworth biquad, fc_filter.c).

Why a model here: `tune notch` chooses the harmonics to notch by what each line
would leave after the filters, predicts the filtered noise from the raw spectrum
before it flies, and reports the phase the chain costs at the loop's crossover.
numpy only, so the light install runs it.

Both filters are bilinear transforms pre-warped at their own design frequency, so
at a frequency f the digital response equals the analogue prototype's at
Omega = tan(pi f / fs) with every design frequency mapped the same way (the
transform's 2/T cancels). Notch prototype (ArduPilot's NotchFilter):
    H(s) = (s^2 + A^2 (w0/Q) s + w0^2) / (s^2 + (w0/Q) s + w0^2),  A = 10^(-ATT/40)
so the centre is ATT dB down; Q from the -3 dB width BW at FREQ taken as an octave
width: r = FREQ / (FREQ - BW/2), Q = r / (r^2 - 1). Q is shared by every harmonic
and centre (constant Q), and a harmonic at or above 0.48 fs is left out, as the core
does.
"""

from __future__ import annotations

import dataclasses

import numpy as np

HARMONIC_MAX_FRACTION = 0.48    # of the sample rate: the core switches such a harmonic off


@dataclasses.dataclass(frozen=True)
class NotchDesign:
    """One harmonic notch at a fixed centre (its hover centre for MODE 1 and 3)."""

    center_hz: float        # fundamental's centre [Hz]
    bw_hz: float            # -3 dB bandwidth at the centre [Hz]
    att_db: float           # depth at the centre [dB]
    harmonics: int          # HMNCS bitmask: bit k = the (k+1)-th harmonic

    def centers_hz(self, rate_hz: float) -> list[float]:
        """The notches' centres the core runs at this sample rate."""
        out = []
        for k in range(16):
            f = (k + 1) * self.center_hz
            if self.harmonics >> k & 1 and f < HARMONIC_MAX_FRACTION * rate_hz:
                out.append(f)
        return out

    @property
    def q(self) -> float:
        r = self.center_hz / (self.center_hz - 0.5 * self.bw_hz)
        return r / (r * r - 1.0)


def _omega(f_hz, rate_hz: float):
    return np.tan(np.pi * np.asarray(f_hz, dtype=np.float64) / rate_hz)


def notch_response(f_hz, design: NotchDesign | None, rate_hz: float) -> np.ndarray:
    """Complex response of the notch bank at f_hz (1 without a notch)."""
    f = np.asarray(f_hz, dtype=np.float64)
    h = np.ones(f.shape, dtype=np.complex128)
    if design is None:
        return h
    s = 1j * _omega(f, rate_hz)
    a2 = 10.0 ** (-design.att_db / 20.0)
    for fc in design.centers_hz(rate_hz):
        w0 = _omega(fc, rate_hz)
        damp = w0 / design.q
        h *= (s * s + a2 * damp * s + w0 * w0) / (s * s + damp * s + w0 * w0)
    return h


def lpf_response(f_hz, cutoff_hz: float, rate_hz: float) -> np.ndarray:
    """Complex response of the gyro low-pass (cutoff 0: off, as INS_GYRO_FILTER 0)."""
    f = np.asarray(f_hz, dtype=np.float64)
    if not cutoff_hz > 0:
        return np.ones(f.shape, dtype=np.complex128)
    s = 1j * _omega(f, rate_hz)
    wc = _omega(cutoff_hz, rate_hz)
    return wc * wc / (s * s + np.sqrt(2.0) * wc * s + wc * wc)


def chain_response(f_hz, design: NotchDesign | None, cutoff_hz: float,
                   rate_hz: float) -> np.ndarray:
    """Notch bank then low-pass, as fc_ins applies them."""
    return notch_response(f_hz, design, rate_hz) * lpf_response(f_hz, cutoff_hz, rate_hz)


def phase_lag_deg(f_hz: float, design: NotchDesign | None, cutoff_hz: float,
                  rate_hz: float) -> float:
    """How many degrees the chain delays a tone at f_hz (positive = lag)."""
    return float(-np.degrees(np.angle(chain_response(f_hz, design, cutoff_hz, rate_hz))))
