"""The vibration summary of a log: per IMU channel, sensor and axis, the spectrum's peaks.

One plain dict (JSON as is) that `silbridge analyze --spectrum` prints as a table or as
JSON, and the HTML report quotes. Shape:

  {"window_s": [a, b], "window_note": str, "segment_s", "overlap", "window_fn": "hann",
   "min_hz", "rotor": {"source", "median_hz", "per_motor_hz", "spread_hz",
   "harmonics_hz": {"1": f, "2": 2f, "3": 3f}} or null, "rotor_note": str,
   "channels": [{"channel", "rate_hz", "resolution_hz", "segment_n", "segments",
                 "axes": {"gyro_x": {"unit", "band_rms", "peaks": [{"freq_hz", "amp",
                 "harmonic", "order"}]}, ...}}]}

`harmonic` is k when the peak sits at k x the rotor frequency (tools/logs/spectrum_peaks.py
says within what), `order` the peak's frequency over the rotor's; both null without rotor
speed. With the chip's raw channel in the log, the FC channel's peaks also carry
`alias_of_hz`: the true frequency of the raw peak above the FC's Nyquist that folds onto
them, or null (tools/logs/spectrum_alias.py). `band_rms` is the RMS from min_hz to Nyquist, in the sensor's unit. With track
(throttle changes): each channel gains "track": {"segment_s", "resolution_hz", "segments",
"rotor_hz_range"} and each axis "track": [{"k", "segments", "found", "median_dev_pct",
"max_dev_pct"}] for k = 1, 2, 3 (tools/logs/spectrum_track.py).
"""

from __future__ import annotations

from silbridge.tools.logs.spectrum import OVERLAP, band_rms
from silbridge.tools.logs.spectrum_alias import mark_aliases
from silbridge.tools.logs.spectrum_log import (AXES, NO_ROTOR, ROTOR_CHANNEL, SENSORS,
                                               SpectrumError, channel_rows, channel_spectra,
                                               imu_channels, rotor_ref, rotor_series)
from silbridge.tools.logs.spectrum_peaks import MIN_HZ, find_peaks, label_peaks
from silbridge.tools.logs.spectrum_track import track_harmonics

HARMONICS_MARKED = (1, 2, 3)    # 1x imbalance, 2x blade pass of a two-blade prop, 3x


def _rotor_dict(ref) -> dict | None:
    if ref is None:
        return None
    return {"source": ROTOR_CHANNEL, "median_hz": ref.median_hz,
            "per_motor_hz": ref.per_motor_hz, "spread_hz": ref.spread_hz,
            "harmonics_hz": {str(k): k * ref.median_hz for k in HARMONICS_MARKED}}


def _axes(spectra: dict, ref, peaks: int, min_hz: float) -> dict:
    out = {}
    for sensor, sp in spectra.items():
        rms = band_rms(sp, min_hz)
        for i, ax in enumerate(AXES):
            found = find_peaks(sp.freq_hz, sp.amp[:, i], peaks, min_hz)
            labelled = label_peaks(found, None if ref is None else ref.median_hz,
                                   sp.resolution_hz, 0.0 if ref is None else ref.spread_hz)
            out[f"{sensor}_{ax}"] = {
                "unit": SENSORS[sensor][1], "band_rms": float(rms[i]),
                "peaks": [{"freq_hz": p.freq_hz, "amp": p.amp, "harmonic": p.harmonic,
                           "order": p.order} for p in labelled]}
    return out


def _tracks(log, channel: str, a_s: float, b_s: float, sensors: list[str],
            min_hz: float) -> tuple[dict, dict]:
    """The harmonics followed segment by segment (tools/logs/spectrum_track.py):
    (the segments' description, axis -> [per harmonic])."""
    rows, rate = channel_rows(log, channel, a_s, b_s)
    rotor_t, rotor_hz = rotor_series(log, a_s, b_s)
    segments, per_axis = {}, {}
    for sensor in sensors:
        tr = track_harmonics(rows[SENSORS[sensor][0]], rate, rows["sim_ns"][0] * 1e-9,
                             rotor_t, rotor_hz, HARMONICS_MARKED, min_hz)
        for i, ax in enumerate(AXES):
            per_axis[f"{sensor}_{ax}"] = tr["axes"][i]
        segments = {k: v for k, v in tr.items() if k != "axes"}
    return segments, per_axis


def vibration_summary(log, window: tuple[float, float, str], segment_s: float,
                      sensors: list[str], peaks: int, min_hz: float = MIN_HZ,
                      track: bool = False) -> dict:
    """The summary of the module docstring over window = (start, end, note); with track,
    each axis also carries "track" and each channel "track" (its segments)."""
    a_s, b_s, note = window
    channels = imu_channels(log)
    if not channels:
        raise SpectrumError(f"{log.path} has no IMU channel (/imu with gyro and accel "
                            "rows); pass the log of a silbridge flight")
    if not segment_s > 0:
        raise SpectrumError(f"segment length {segment_s:g} s: give --segment-s > 0")
    ref = rotor_ref(log, a_s, b_s)
    if track and ref is None:
        raise SpectrumError(f"{NO_ROTOR} ({ROTOR_CHANNEL}) within {a_s:g}-{b_s:g} s: --track "
                            "follows the rotor harmonics and needs it; leave --track out")
    out = {"window_s": [a_s, b_s], "window_note": note, "segment_s": segment_s,
           "overlap": OVERLAP, "window_fn": "hann", "min_hz": min_hz,
           "rotor": _rotor_dict(ref), "rotor_note": "" if ref else NO_ROTOR, "channels": []}
    for name in channels:
        rate, spectra = channel_spectra(log, name, a_s, b_s, segment_s, sensors)
        sp = next(iter(spectra.values()))
        entry = {"channel": name, "rate_hz": rate, "resolution_hz": sp.resolution_hz,
                 "segment_n": sp.segment_n, "segments": sp.segments,
                 "axes": _axes(spectra, ref, peaks, min_hz)}
        if track:
            entry["track"], per_axis = _tracks(log, name, a_s, b_s, sensors, min_hz)
            for axis, rows in per_axis.items():
                entry["axes"][axis]["track"] = rows
        out["channels"].append(entry)
    mark_aliases(out["channels"])
    return out
