"""The in-flight FFT (fc_fft.h) driven from Python for the tests, through the cffi bindings
of the core's own sources (core_cffi.py)."""

from __future__ import annotations

import numpy as np

from core_cffi import ffi, lib

# ArduPilot's gyro window unit: int16 counts of a +-2000 deg/s gyro, per rad/s.
COUNTS_PER_RAD_S = 32767.0 / np.radians(2000.0)
# ArduCopter 4.6's FFT_* defaults (fc_params.def), as the config fields.
DEFAULTS = dict(enable=True, min_hz=80.0, max_hz=200.0, sample_mode=0, window_size=32,
                window_overlap=0.5, freq_hover_hz=80.0, thr_ref=0.35, snr_ref_db=25.0,
                att_ref_db=15.0, bw_hover_hz=20.0, hmnc_fit_pct=10.0, hmnc_peak=0,
                num_frames=0, options=0, harmonics=3, notches=1)


class GyroFft:
    """One fc_fft_t: push gyro rows (rad/s) and step once per row, as fc_core_imu_step."""

    def __init__(self, fs_hz: float = 1000.0, loop_hz: float | None = None, **cfg):
        self.cfg = ffi.new("fc_fft_config_t *")
        for k, v in {**DEFAULTS, **cfg}.items():
            setattr(self.cfg, k, v)
        self.f = ffi.new("fc_fft_t *")
        lib.fc_fft_init(self.f, self.cfg, fs_hz, loop_hz or fs_hz)
        self._g = ffi.new("float[3]")

    def push(self, rows) -> None:
        """Samples into the history only (no analysis work)."""
        for row in np.asarray(rows, dtype=np.float32):
            self._g[0], self._g[1], self._g[2] = row
            lib.fc_fft_push(self.f, self._g)

    def feed(self, rows) -> np.ndarray:
        """Each row pushed then one step; returns the units each step spent."""
        rows = np.asarray(rows, dtype=np.float32)
        units = np.empty(len(rows), dtype=np.int64)
        for i, row in enumerate(rows):
            self._g[0], self._g[1], self._g[2] = row
            lib.fc_fft_push(self.f, self._g)
            lib.fc_fft_step(self.f)
            units[i] = self.f.last_units
        return units

    def spectrum_bins(self) -> np.ndarray:
        """The complex bins of the frame just transformed (natural order)."""
        n = self.f.n
        return np.frombuffer(ffi.buffer(self.f.re, 4 * n), np.float32) \
            + 1j * np.frombuffer(ffi.buffer(self.f.im, 4 * n), np.float32)

    def track_hz(self, axis: int, slot: int) -> float:
        return float(self.f.track[axis][slot].freq_hz)

    def center_hz(self, throttle: float = 0.3) -> float:
        return float(lib.fc_fft_center_freq_hz(self.f, throttle))

    def notch_freqs(self, throttle: float = 0.3) -> list[float]:
        out = ffi.new("float[3]")
        n = lib.fc_fft_notch_freqs(self.f, throttle, out)
        return [float(out[i]) for i in range(n)]


def tones(fs_hz: float, seconds: float, parts, gains=(1.0, 0.8, 0.3), noise=0.0, seed=1):
    """Gyro rows [rad/s]: sum of (hz, amplitude, phase) sines on roll, scaled per axis, plus
    white noise of `noise` rad/s RMS."""
    t = np.arange(int(round(fs_hz * seconds))) / fs_hz
    sig = sum(a * np.sin(2 * np.pi * hz * t + ph) for hz, a, ph in parts) if parts else 0 * t
    rng = np.random.default_rng(seed)
    rows = np.stack([g * sig for g in gains], axis=1)
    return rows + noise * rng.standard_normal(rows.shape)
