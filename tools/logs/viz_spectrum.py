"""The viewable vibration channel: the IMU's spectrum, summarised 10 times a second.

Foxglove's Plot panel plots one value per message over time, not a spectrum. So every
PERIOD_NS of sim time the last WINDOW_S of /imu samples (Hann window, mean removed, as
tools/logs/spectrum.py does per segment) is reduced, per sensor and body axis, to three
numbers that plot well over a flight:

  <sensor>_<axis>_peak_hz     the largest bin at or above MIN_HZ (the vibration band)
  <sensor>_<axis>_peak_<u>    its amplitude, as an equivalent sinusoid [rad/s or m/s^2]
  <sensor>_<axis>_rms_<u>     the RMS of the band MIN_HZ..Nyquist (Parseval over the window)

With E's /viz/rotor (m1_rpm ...) beside it, a peak frequency that follows the rotor
frequency is a rotor harmonic. The message at time T covers the samples up to T.
Frequency steps: 1 / WINDOW_S (4 Hz); the full spectrum is `silbridge analyze --spectrum`'s.
Cost: ~0.3 ms CPU per second of sim time at a 1 kHz IMU (docs/howto/vibration-spectrum.md).
"""

from __future__ import annotations

import numpy as np

from silbridge.shm.records import NS_PER_S
from silbridge.tools.logs.spectrum import hann
from silbridge.tools.logs.spectrum_peaks import MIN_HZ

VIBRATION_CHANNEL = "/viz/vibration"
SOURCE = "/imu"
PERIOD_NS = NS_PER_S // 10      # 10 Hz: the rate a person reads a trend at
WINDOW_S = 0.25                 # 4 Hz bins; overlapping windows, 2.5 per message period
# sensor -> (column, unit suffix, unit text); axes are body FRD.
_SENSORS = {"gyro": ("gyro_frd_rad_s", "rad_s", "rad/s"),
            "accel": ("accel_frd_m_s2", "m_s2", "m/s^2")}


def _fields() -> list[tuple[str, str]]:
    out = []
    for sensor, (_col, suffix, unit) in _SENSORS.items():
        for ax in "xyz":
            out += [(f"{sensor}_{ax}_peak_hz", f"largest {sensor} {ax} peak >= {MIN_HZ:g} Hz"),
                    (f"{sensor}_{ax}_peak_{suffix}", f"its amplitude [{unit}]"),
                    (f"{sensor}_{ax}_rms_{suffix}", f"{sensor} {ax} RMS >= {MIN_HZ:g} Hz [{unit}]")]
    return out


# The PLOTS entry of tools/logs/viz_log.py: (schema, source channel, fields).
PLOT = ("silbridge_msgs/msg/VizVibration", SOURCE, _fields())
SOURCE_FIELDS = tuple(col for col, _s, _u in _SENSORS.values())


class VibrationView:
    """Keeps the last window of samples across batches and summarises it every period."""

    def __init__(self, viz_hz: float):
        # At most PERIOD_NS apart, fewer when the log's --viz-hz asks for less.
        self._period = max(PERIOD_NS, int(round(NS_PER_S / viz_hz)))
        self._t = np.zeros(0, dtype=np.int64)
        self._x = np.zeros((0, 6))
        self._next_ns = self._period
        self._n = 0                 # samples per window, from the first time steps seen
        self._dt_s = 0.0            # their median step [s]
        self._w = self._freq = None  # window and bin frequencies, made once per length
        self._band = 0

    def batch(self, rows: np.ndarray) -> tuple[np.ndarray, dict] | None:
        """(message times, field -> values) of the periods this batch completes, or None."""
        x = np.hstack([np.asarray(rows[c], dtype=np.float64) for c in SOURCE_FIELDS])
        self._t = np.concatenate([self._t, rows["sim_ns"]])
        self._x = np.concatenate([self._x, x])
        if not self._n:
            steps = np.diff(self._t)
            steps = steps[steps > 0]
            if not len(steps):              # no time step seen yet: nothing to summarise
                return None
            self._dt_s = float(np.median(steps)) / NS_PER_S
            self._n = max(int(round(WINDOW_S / self._dt_s)), 8)
        due = np.arange(self._next_ns, int(self._t[-1]) + 1, self._period, dtype=np.int64)
        self._next_ns = int(due[-1]) + self._period if len(due) else self._next_ns
        ends = np.searchsorted(self._t, due, side="right")      # samples up to each time
        full = ends >= self._n
        due, ends = due[full], ends[full]
        out = (due, self._summarise(ends)) if len(due) else None
        keep = max(len(self._t) - self._n, 0)
        self._t, self._x = self._t[keep:], self._x[keep:]
        return out

    def _summarise(self, ends: np.ndarray) -> dict:
        n = self._n
        if self._w is None or len(self._w) != n:
            self._w = hann(n)
            self._freq = np.fft.rfftfreq(n, self._dt_s)
            self._band = int(np.searchsorted(self._freq, MIN_HZ))
        w = self._w
        # Windows as (k, 6, n) views; no mean removal: a periodic Hann window keeps the
        # mean in bins 0 and 1, below the band (MIN_HZ is several bins up).
        seg = np.lib.stride_tricks.sliding_window_view(self._x, n, axis=0)[ends - n]
        spec = np.fft.rfft(seg * w, axis=2)[:, :, self._band:]          # (k, 6, n_band)
        power = spec.real ** 2 + spec.imag ** 2
        top = power.argmax(axis=2)                                      # (k, 6)
        peak = 2.0 * np.sqrt(np.take_along_axis(power, top[:, :, None], 2)[:, :, 0]) / w.sum()
        # Parseval with the window's power: sum |X|^2 over both sides / (n sum w^2).
        rms = np.sqrt(2.0 * power.sum(axis=2) / (n * (w * w).sum()))
        freq = self._freq[self._band:]
        out, col = {}, 0
        for sensor, (_c, suffix, _u) in _SENSORS.items():
            for ax in "xyz":
                out[f"{sensor}_{ax}_peak_hz"] = freq[top[:, col]]
                out[f"{sensor}_{ax}_peak_{suffix}"] = peak[:, col]
                out[f"{sensor}_{ax}_rms_{suffix}"] = rms[:, col]
                col += 1
        return out
