"""A run log's vibration: IMU spectra, their peaks and the rotor harmonics, as one dict.

Reads from a RunLog (tools/logs/log_reader.py):
- the IMU as the FC read it (`/imu`, the FC's rate) and, when the log has it, the raw
  samples at the chip's output data rate (`RAW_IMU_CHANNEL`): rows `sim_ns`,
  `gyro_frd_rad_s`, `accel_frd_m_s2`;
- rotor speed (`/rotor`, `omega_rad_s` per motor, tools/logs/rotor_log.py) when the log has
  it: the reference of the harmonics is the median rotor frequency of all motors over the
  window, their spread (half the 10-90 % range) widens the match. Without it the peaks
  carry no harmonic and the report says "no rotor speed in this log".
The sample rate of a channel is read from its sim_ns steps (the median), so a chip channel
needs no configuration key. The maths: tools/logs/spectrum.py, spectrum_peaks.py.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from silbridge.tools.logs.imu_raw_log import RAW_IMU_CHANNEL
from silbridge.tools.logs.rotor_log import ROTOR_CHANNEL
from silbridge.tools.logs.spectrum import Spectrum, welch

IMU_CHANNEL = "/imu"
# sensor -> (column, unit); axes are body FRD.
SENSORS = {"gyro": ("gyro_frd_rad_s", "rad/s"), "accel": ("accel_frd_m_s2", "m/s^2")}
AXES = "xyz"
NO_ROTOR = "no rotor speed in this log"


class SpectrumError(Exception):
    """The log or the window cannot give a spectrum; the message says what to change."""

    user_facing = True


@dataclasses.dataclass(frozen=True)
class RotorRef:
    """Rotor frequency over a window [Hz]."""

    median_hz: float        # all motors, all samples
    per_motor_hz: list      # median of each motor
    spread_hz: float        # half the 10 %..90 % range of all samples
    samples: int


def imu_channels(log) -> list[str]:
    """The IMU channels of the log that hold both sensors: FC rate first, then the chip."""
    out = []
    for name in (IMU_CHANNEL, RAW_IMU_CHANNEL):
        rows = log.channels.get(name)
        if rows is not None and len(rows) and all(c in rows.dtype.names
                                                  for c, _ in SENSORS.values()):
            out.append(name)
    return out


def sample_rate_hz(sim_ns: np.ndarray) -> float:
    """The rate of a channel from its median sample spacing."""
    step = float(np.median(np.diff(sim_ns)))
    if not step > 0:
        raise SpectrumError("the IMU samples' sim times do not advance (median step "
                            f"{step:g} ns); pass the log of a silbridge flight")
    return 1e9 / step


def window_of(log, asked: tuple[float, float] | None, default: tuple[float, float]
              ) -> tuple[float, float, str]:
    """(start, end, note) in s of sim time. An asked window must overlap the log; its end
    is cut to the log's. Without one, `default` (the metrics' analysis window) is cut the
    same way, or replaced by the log's second half when the log ends before it."""
    end_s = log.duration_s()
    a, b = asked if asked is not None else default
    if b <= a:
        raise SpectrumError(f"spectrum window {a:g}-{b:g} s is empty; give START END "
                            "with END > START")
    if a >= end_s or b <= 0:
        if asked is not None:
            raise SpectrumError(f"spectrum window {a:g}-{b:g} s lies outside the log "
                                f"(0-{end_s:.3f} s); give --spectrum-window inside it")
        return end_s / 2, end_s, (f"log ends at {end_s:.3f} s, before the analysis window "
                                  f"{a:g}-{b:g} s: used its second half")
    if b > end_s:
        return a, end_s, f"window {a:g}-{b:g} s cut to {a:g}-{end_s:.3f} s (the log ends there)"
    return a, b, ""


def rows_in(rows: np.ndarray, a_s: float, b_s: float) -> np.ndarray:
    """The rows with a_s <= sim time <= b_s."""
    t = rows["sim_ns"]
    lo = np.searchsorted(t, a_s * 1e9, side="left")
    hi = np.searchsorted(t, b_s * 1e9, side="right")
    return rows[lo:hi]


def rotor_series(log, a_s: float = 0.0, b_s: float = np.inf
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """(t_s, rotor frequency [Hz] of each motor (n, 4)) within the window, None when the
    log has no rotor speed there."""
    rows = log.channels.get(ROTOR_CHANNEL)
    if rows is None or "omega_rad_s" not in (rows.dtype.names or ()):
        return None
    rows = rows_in(rows, a_s, b_s)
    if not len(rows):
        return None
    return rows["sim_ns"] * 1e-9, np.asarray(rows["omega_rad_s"], np.float64) / (2.0 * np.pi)


def rotor_ref(log, a_s: float, b_s: float) -> RotorRef | None:
    """The rotor frequency over the window, None when the log has no rotor speed there."""
    series = rotor_series(log, a_s, b_s)
    if series is None:
        return None
    hz = series[1]
    p10, p90 = np.percentile(hz, [10, 90])
    return RotorRef(median_hz=float(np.median(hz)),
                    per_motor_hz=[float(v) for v in np.median(hz, axis=0)],
                    spread_hz=float(0.5 * (p90 - p10)), samples=len(hz))


def channel_rows(log, channel: str, a_s: float, b_s: float) -> tuple[np.ndarray, float]:
    """(rows within the window, their sample rate); at least two rows."""
    rows = rows_in(log.channels[channel], a_s, b_s)
    if len(rows) < 2:
        raise SpectrumError(f"{channel} has {len(rows)} samples in {a_s:g}-{b_s:g} s; "
                            "choose a window where the IMU was logged")
    return rows, sample_rate_hz(rows["sim_ns"])


def channel_spectra(log, channel: str, a_s: float, b_s: float, segment_s: float,
                    sensors: list[str]) -> tuple[float, dict[str, Spectrum]]:
    """(sample rate, sensor -> Welch spectrum of its three axes) over the window."""
    rows, rate = channel_rows(log, channel, a_s, b_s)
    n = int(round(segment_s * rate))
    if n > len(rows):
        raise SpectrumError(f"{channel}: {len(rows)} samples in {a_s:g}-{b_s:g} s, fewer than "
                            f"one {segment_s:g} s segment; widen the window or shorten "
                            "--segment-s")
    return rate, {s: welch(rows[SENSORS[s][0]], rate, n) for s in sensors}
