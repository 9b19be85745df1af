"""Table 1's noise metrics: how much high-frequency content the FC lets through, from a log.

Each is the RMS of a signal over one band, NOISE_BAND_LO_HZ (20 Hz) up to the Nyquist
frequency of the signal as logged, from its Welch spectrum (tools/logs/spectrum.py: 1 s Hann
segments, 50 % overlap, segment means removed): RMS = sqrt(sum of the one-sided PSD over the
bins in the band x bin spacing).

Why this band:
- below 20 Hz is control: the attitude loops act up to ~10 Hz (the same floor as the
  spectrum's peak finder, tools/logs/spectrum_peaks.py MIN_HZ), so what an FC does there is
  flying, not noise;
- up to the log's own Nyquist frequency, not a fixed 200 Hz: ArduCopter's 400 Hz output is
  logged per 1 kHz physics step and held for 2-3 steps. The hold keeps the output's values,
  hence its power, but moves part of it above 200 Hz (a 120 Hz tone held so reads 12 % low
  below 200 Hz, and within 0.01 % up to 500 Hz). Up to Nyquist, a held 400 Hz output and
  the same output logged at 400 Hz read the same; a faster controller's own content above
  200 Hz is real motor-output noise and counts.
- A pure tone at f in the band, at least two bins (2 Hz) from either edge, reads its exact
  RMS A / sqrt(2): a Hann window spreads it over +-2 bins and the PSD sum keeps its power.

The signals (NaN when the log lacks them: ArduCopter and PX4 logs carry PWM and the sensor
IMU, not their filtered gyro or D term, docs/reference/metrics.md says why):
  gyro_noise_dps        our FC's filtered, bias-corrected gyro of the rate loop (/fc/status
                        rate_frd_rad_s, one row per PWM tick), root sum square of the three
                        axes' band RMS [deg/s]; gyro_noise_{roll,pitch,yaw}_dps per axis
  gyro_in_noise_dps     the same of the sensor IMU the FC read (/imu gyro_frd_rad_s): what
                        the filters were given. Not the same for two FCs on one seed: the
                        vibration follows each FC's own rotor speeds
  dterm_noise_us        the rate loop's D terms (/fc/status pid_d, three axes), root sum
                        square [us of mixer input]
  motor_noise_us        each motor's published PWM (/pwm pwm_us), band RMS; the mean over
                        the motors; motor_noise_max_us the largest motor's [us]
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.tools.logs.spectrum import band_rms, welch

NOISE_BAND_LO_HZ = 20.0
SEGMENT_S = 1.0          # 1 Hz bins: the band's edges are sharp to a bin or two
MIN_SEGMENT_S = 0.25     # shorter: bins wider than 4 Hz, too coarse to cut at 20 Hz
NAN = float("nan")
KEYS = ("gyro_noise_dps", "gyro_noise_roll_dps", "gyro_noise_pitch_dps", "gyro_noise_yaw_dps",
        "gyro_in_noise_dps", "dterm_noise_us", "motor_noise_us", "motor_noise_max_us")


def band_noise(x: np.ndarray, rate_hz: float, lo_hz: float = NOISE_BAND_LO_HZ) -> np.ndarray:
    """RMS of each column of x (evenly sampled at rate_hz) from lo_hz to the Nyquist
    frequency. NaN per column when x is too short for one segment, holds a non-finite value,
    or lo_hz is not below the Nyquist frequency."""
    x = np.asarray(x, dtype=np.float64)
    cols = 1 if x.ndim == 1 else x.shape[1]
    if not math.isfinite(rate_hz) or rate_hz / 2.0 <= lo_hz:
        return np.full(cols, NAN)
    segment_n = min(int(round(SEGMENT_S * rate_hz)), len(x))
    if segment_n < MIN_SEGMENT_S * rate_hz or not np.all(np.isfinite(x)):
        return np.full(cols, NAN)
    return band_rms(welch(x, rate_hz, segment_n), lo_hz)


def vector_rms(per_axis: np.ndarray) -> float:
    """The RMS of the vector's magnitude, from its axes' RMS: sqrt(sum of squares)."""
    return float(math.sqrt(float(np.sum(np.square(per_axis)))))


def _rate_hz(rows) -> float:
    """Sample rate of a channel from its median row spacing (rows are evenly spaced in
    sim time in every log we write; the median ignores a missing row)."""
    if rows is None or len(rows) < 2:
        return NAN
    dt = np.median(np.diff(rows["sim_ns"]))
    return 1e9 / float(dt) if dt > 0 else NAN


def _field(rows, name: str):
    if rows is None or not len(rows) or name not in rows.dtype.names:
        return None
    return rows[name].astype(np.float64)


def _gyro(status, imu) -> dict:
    out = {}
    rate = _field(status, "rate_frd_rad_s")
    axes = band_noise(np.degrees(rate), _rate_hz(status)) if rate is not None \
        else np.full(3, NAN)
    for name, v in zip(("roll", "pitch", "yaw"), axes):
        out[f"gyro_noise_{name}_dps"] = float(v)
    out["gyro_noise_dps"] = vector_rms(axes)
    raw = _field(imu, "gyro_frd_rad_s")
    out["gyro_in_noise_dps"] = vector_rms(band_noise(np.degrees(raw), _rate_hz(imu))) \
        if raw is not None else NAN
    return out


def _motors(pwm) -> dict:
    us = _field(pwm, "pwm_us")
    if us is None:
        return {"motor_noise_us": NAN, "motor_noise_max_us": NAN}
    nch = int(pwm["channel_count"].max()) if "channel_count" in pwm.dtype.names else 4
    per_motor = band_noise(us[:, :max(nch, 1)], _rate_hz(pwm))
    return {"motor_noise_us": float(np.mean(per_motor)),
            "motor_noise_max_us": float(np.max(per_motor))}


def noise_metrics(log, win: tuple[float, float]) -> dict:
    """Every key of KEYS over the time window win [s] of a RunLog (NaN where absent)."""
    from silbridge.tools.benchmark.metrics import _select

    status = _select(log, "/fc/status", win)
    out = _gyro(status, _select(log, "/imu", win))
    d = _field(status, "pid_d")
    out["dterm_noise_us"] = vector_rms(band_noise(d, _rate_hz(status))) if d is not None \
        else NAN
    out.update(_motors(_select(log, "/pwm", win)))
    return out
