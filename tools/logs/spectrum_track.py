"""Rotor harmonics followed through throttle changes: one short spectrum per segment.

A Welch average over a window in which the throttle moves smears each harmonic over the
range the rotor swept, and the median rotor frequency no longer names it. Here the
window is cut into short Hann segments (a spectrogram, tools/logs/spectrum.py); in each
segment the rotor frequency is the motors' median over the segment's span, and for each
harmonic k the largest bin within +-SEARCH of k x that frequency is taken, refined
between bins as the peak finder does (tools/logs/spectrum_peaks.py). It counts as found
when it stands FLOOR_FACTOR above the segment's median amplitude in the band. Per axis and
k the result says in how many segments the harmonic was found, and how far its frequency
sat from k x the rotor's (median and largest deviation, in % of k x f_rot), over the
rotor frequency range the window covered.
"""

from __future__ import annotations

import numpy as np

from silbridge.tools.logs.spectrum import spectrogram
from silbridge.tools.logs.spectrum_peaks import FLOOR_FACTOR, refine

SEARCH = 0.05           # +-5 % of k f_rot: the motors' spread in a manoeuvre, no neighbour k
TRACK_SEGMENT_S = 0.25  # 4 Hz bins every 0.125 s: a throttle step settles in ~0.1 s (motor lag)


def rotor_at(t_s: np.ndarray, half_s: float, rotor_t_s: np.ndarray,
             rotor_hz: np.ndarray) -> np.ndarray:
    """Median over motors of each motor's mean rotor frequency within t +- half_s."""
    lo = np.searchsorted(rotor_t_s, t_s - half_s, side="left")
    hi = np.searchsorted(rotor_t_s, t_s + half_s, side="right")
    csum = np.vstack([np.zeros((1, rotor_hz.shape[1])), np.cumsum(rotor_hz, axis=0)])
    n = np.maximum(hi - lo, 1)[:, None]
    means = (csum[hi] - csum[lo]) / n
    return np.where(hi > lo, np.median(means, axis=1), np.nan)


def _track_axis(freq: np.ndarray, amp: np.ndarray, f_rot: np.ndarray, k: int,
                min_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(deviation of the peak from k f_rot [fraction], found) per segment; amp (n_seg, n_bins)."""
    df = freq[1] - freq[0]
    band = freq >= min_hz
    dev = np.full(len(f_rot), np.nan)
    found = np.zeros(len(f_rot), dtype=bool)
    for s, fr in enumerate(f_rot):
        target = k * fr
        if not np.isfinite(target) or target + 2 * df > freq[-1] or target < min_hz:
            continue
        half = max(SEARCH * target, 2 * df)
        near = np.flatnonzero((freq >= target - half) & (freq <= target + half))
        i = int(near[np.argmax(amp[s, near])])
        d, _gain = refine(amp[s], i)
        dev[s] = (freq[i] + d * df) / target - 1.0
        found[s] = amp[s, i] > FLOOR_FACTOR * np.median(amp[s, band])
    return dev, found


def track_harmonics(x: np.ndarray, rate_hz: float, t0_s: float, rotor_t_s: np.ndarray,
                    rotor_hz: np.ndarray, harmonics, min_hz: float,
                    segment_s: float = TRACK_SEGMENT_S) -> dict:
    """Per axis of x (n, n_axes) -> [{k, segments, found, median_dev_pct, max_dev_pct}],
    plus the segments' rotor frequency range and resolution."""
    n = int(round(segment_s * rate_hz))
    sg = spectrogram(x, rate_hz, n, t0_s)
    f_rot = rotor_at(sg.t_s, 0.5 * segment_s, rotor_t_s, rotor_hz)
    f_rot[~(f_rot > 0)] = np.nan                # motors stopped: nothing to follow
    out = {"segment_s": segment_s, "resolution_hz": sg.resolution_hz,
           "segments": int(np.isfinite(f_rot).sum()),
           "rotor_hz_range": [float(np.nanmin(f_rot)), float(np.nanmax(f_rot))]
           if np.isfinite(f_rot).any() else None, "axes": []}
    for a in range(sg.amp.shape[2]):
        rows = []
        for k in harmonics:
            dev, found = _track_axis(sg.freq_hz, sg.amp[:, :, a], f_rot, k, min_hz)
            d = np.abs(dev[found]) * 100.0
            rows.append({"k": k, "segments": int(np.isfinite(dev).sum()),
                         "found": int(found.sum()),
                         "median_dev_pct": float(np.median(d)) if len(d) else None,
                         "max_dev_pct": float(d.max()) if len(d) else None})
        out["axes"].append(rows)
    return out
