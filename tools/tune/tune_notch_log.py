"""What `tune notch` reads from a hover log: the evidence for the proposal
(vibration lines of the raw gyro, rotor speed, hover throttle, ESC telemetry) and
the measure it is judged by, the gyro noise after filtering.

Gyro noise after filtering: Table 1's gyro_noise_dps (tools/benchmark/noise.py, one
definition): the rate loop's own gyro (/fc/status rate_frd_rad_s: after the notches and
INS_GYRO_FILTER, bias removed), one sample per PWM tick, RMS per axis from
NOISE_BAND_LO_HZ (20 Hz) to that channel's Nyquist (Welch, 1 s Hann segments),
combined over the axes as sqrt(roll^2 + pitch^2 + yaw^2), in deg/s; a change in dB is
20 log10(after / before).

The hover window: by default the scenario's steady part (from its transient_end_s) to
the log's end, starting no later than the log's midpoint so a short flight still gives
half its length (tools/logs/spectrum_log.window_of cuts and checks it).
"""

from __future__ import annotations

import numpy as np

from silbridge.fc_sil import params as P
from silbridge.tools.benchmark.noise import NOISE_BAND_LO_HZ, band_noise, vector_rms
from silbridge.tools.logs.spectrum_log import (AXES, SENSORS, SpectrumError, channel_spectra,
                                               rotor_ref, rotor_series, rows_in,
                                               sample_rate_hz, window_of)
from silbridge.tools.logs.spectrum_peaks import MIN_HZ, find_peaks, harmonic_of
from silbridge.tools.tune.tune_notch_propose import Line, NotchEvidence

CHANNELS = ["/imu", "/fc/status", "/rotor", "/esc"]
STATUS = "/fc/status"
SEGMENT_S = 1.0             # Welch segment: 1 Hz bins, as `analyze --spectrum`
PEAKS_PER_AXIS = 5          # the rotor's 1x..3x and room for a resonance
DEFAULT_STEADY_FROM_S = 30.0    # a log without scenario windows: the benchmark's default


def hover_window(log, asked: tuple[float, float] | None) -> tuple[float, float, str]:
    windows = (log.metadata.get("scenario") or {}).get("windows") or {}
    start = float(windows.get("transient_end_s", DEFAULT_STEADY_FROM_S))
    return window_of(log, asked, (min(start, 0.5 * log.duration_s()), float("inf")))


def flown_param(log, name: str) -> float:
    """A parameter as the log's flight had it (its declared default when not recorded)."""
    value = (log.metadata.get("params") or {}).get(name)
    return float(P.BY_NAME[name].default if value is None else value)


def _status_rows(log, a_s: float, b_s: float) -> np.ndarray:
    rows = log.channels.get(STATUS)
    if rows is None or not len(rows_in(rows, a_s, b_s)):
        raise SpectrumError(f"{log.path} has no FC status ({STATUS}) in {a_s:g}-{b_s:g} s; "
                            "pass the log of a silbridge flight (fly --log)")
    return rows_in(rows, a_s, b_s)


def filtered_gyro_noise(log, window) -> dict:
    """The module docstring's measure: {"roll_dps", "pitch_dps", "yaw_dps", "total_dps"},
    the band and the channel's rate."""
    a_s, b_s, _ = window
    rows = _status_rows(log, a_s, b_s)
    rate = sample_rate_hz(rows["sim_ns"])
    axes = band_noise(np.degrees(np.asarray(rows["rate_frd_rad_s"], np.float64)), rate)
    if not np.all(np.isfinite(axes)):
        raise SpectrumError(f"{STATUS}: {len(rows)} samples in {a_s:g}-{b_s:g} s give no "
                            f"spectrum above {NOISE_BAND_LO_HZ:g} Hz; "
                            "fly longer or widen --window")
    out = {f"{name}_dps": float(v) for name, v in zip(("roll", "pitch", "yaw"), axes)}
    out["total_dps"] = vector_rms(axes)
    out["band_hz"] = [NOISE_BAND_LO_HZ, rate / 2.0]
    out["rate_hz"] = rate
    return out


def raw_gyro_spectrum(log, window):
    """Welch spectrum of the gyro as the FC read it (/imu, the notch's input)."""
    a_s, b_s, _ = window
    _, spectra = channel_spectra(log, "/imu", a_s, b_s, SEGMENT_S, ["gyro"])
    return spectra["gyro"]


def gyro_lines(sp, fundamental_hz: float, spread_hz: float) -> tuple:
    """The rotor harmonics among the raw gyro's peaks: per harmonic its strongest axis."""
    best: dict[int, Line] = {}
    for i in range(len(AXES)):
        for f, amp in find_peaks(sp.freq_hz, sp.amp[:, i], PEAKS_PER_AXIS, MIN_HZ):
            k = harmonic_of(f, fundamental_hz, sp.resolution_hz, spread_hz)
            if k is not None and (k not in best or amp > best[k].amp_rad_s):
                best[k] = Line(harmonic=k, freq_hz=f, amp_rad_s=amp)
    return tuple(sorted(best.values(), key=lambda ln: -ln.amp_rad_s))


def _fundamental(log, window, sp) -> tuple[float, float, str]:
    """(rotor frequency at hover, its spread, source): /rotor, else the strongest line."""
    ref = rotor_ref(log, window[0], window[1])
    if ref is not None:
        return ref.median_hz, ref.spread_hz, "/rotor"
    peaks = [p for i in range(len(AXES))
             for p in find_peaks(sp.freq_hz, sp.amp[:, i], 1, MIN_HZ)]
    if not peaks:
        raise SpectrumError("no rotor speed in this log and no line in the gyro spectrum: "
                            "nothing for a notch to take out")
    f, _ = max(peaks, key=lambda p: p[1])
    return f, 0.0, "the strongest gyro line (no rotor speed in this log)"


def _lowest_airborne_hz(log, b_s: float) -> float | None:
    """Lowest rotor frequency from the first airborne tick to b_s (any motor)."""
    st = log.channels.get(STATUS)
    if st is None or not st["airborne"].any():
        return None
    t_air = float(st["sim_ns"][np.argmax(st["airborne"] > 0)]) * 1e-9
    series = rotor_series(log, t_air, b_s)
    return None if series is None else float(series[1].min())


def _hover_throttle(log, window) -> float:
    rows = _status_rows(log, window[0], window[1])
    lo, hi = flown_param(log, "MOT_PWM_MIN"), flown_param(log, "MOT_PWM_MAX")
    return float(np.median((rows["throttle_us"] - lo) / (hi - lo)))


def evidence(log, window) -> tuple[NotchEvidence, object]:
    """(the proposal's evidence, the raw gyro spectrum) over the hover window."""
    if "/imu" not in log.channels or SENSORS["gyro"][0] not in log.channels["/imu"].dtype.names:
        raise SpectrumError(f"{log.path} has no IMU channel (/imu); pass the log of a "
                            "silbridge flight")
    sp = raw_gyro_spectrum(log, window)
    f1, spread, source = _fundamental(log, window, sp)
    esc = log.channels.get("/esc")
    ev = NotchEvidence(imu_rate_hz=sp.rate_hz, fundamental_hz=f1, fundamental_source=source,
                       spread_hz=spread, lowest_hz=_lowest_airborne_hz(log, window[1]),
                       hover_throttle=_hover_throttle(log, window),
                       esc=esc is not None and len(esc) > 0,
                       lines=gyro_lines(sp, f1, spread),
                       gyro_filter_hz=flown_param(log, "INS_GYRO_FILTER"))
    return ev, sp
