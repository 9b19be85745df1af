"""From what a hover log shows (vibration lines, rotor speed, hover throttle, ESC
telemetry) to ArduCopter's harmonic notch and gyro filter parameters.

The rules are ArduPilot's own setup guidance (its wiki pages "Throttle Based Dynamic
Notch Setup", "ESC Telemetry Based Harmonic Notch Setup" and "Managing Gyro Noise with
the Dynamic Harmonic Notch Filters"), restated:
- MODE 1 (throttle), the default: FREQ is the motors' frequency at hover and REF the
  hover throttle, so the centre FREQ sqrt(throttle / REF) follows the rotor as thrust
  (~ rotor speed^2) changes; BW half of FREQ.
- MODE 3 (ESC telemetry), when the log has it: the ESCs give the centre, REF 1 (no
  scaling), FREQ is only the floor below which the notch stops following, so it sits
  at the lowest rotor frequency seen in flight (and above INS_GYRO_FILTER); BW half of
  FREQ, a ratio the core keeps as the centre moves (constant Q).
- HMNCS: the harmonics that show in the spectrum. A line counts when, after the gyro
  low-pass, it is within ATT dB of the strongest line: once the strongest is notched
  ATT dB down, a weaker line left alone adds less than that residual, and a notch on
  it would only cost phase.
- INS_GYRO_FILTER stays where it is while it sits below the notch's lower -3 dB edge
  (the notch handles the lines, the low-pass what lies between and above them);
  above that edge the two would overlap, and it comes down to the edge.
- ATT is left at ArduCopter's default (the caller passes the declared default).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from silbridge.tools.tune.tune_notch_filters import (HARMONIC_MAX_FRACTION, NotchDesign,
                                                     lpf_response)

MODE_THROTTLE = 1
MODE_ESC = 3
BW_OVER_FREQ = 0.5      # ArduPilot's guidance: BW = FREQ / 2


class NotchProposalError(Exception):
    user_facing = True


@dataclasses.dataclass(frozen=True)
class Line:
    """A vibration line of the raw gyro: harmonic k of the rotor, largest over the axes."""

    harmonic: int
    freq_hz: float
    amp_rad_s: float


@dataclasses.dataclass(frozen=True)
class NotchEvidence:
    """What a hover log says about the vibration (tune_notch_log.evidence builds it)."""

    imu_rate_hz: float              # the FC's gyro rate (the notch runs at it)
    fundamental_hz: float           # rotor frequency at hover (1x)
    fundamental_source: str         # where it came from ("/rotor", or the strongest line)
    spread_hz: float                # half the 10-90 % range of the motors' frequencies
    lowest_hz: float | None         # lowest rotor frequency while airborne (MODE 3 floor)
    hover_throttle: float | None    # mixer throttle, fraction of the PWM range
    esc: bool                       # the log has ESC telemetry
    lines: tuple                    # Line, strongest first
    gyro_filter_hz: float           # INS_GYRO_FILTER the log flew with


@dataclasses.dataclass(frozen=True)
class NotchProposal:
    values: dict                    # parameter name -> value, ready for a .parm
    reasons: dict                   # parameter name -> one line: why this value
    design: NotchDesign             # the notch at its hover centre (for predictions)
    mode: int


def significant_harmonics(lines, cutoff_hz: float, rate_hz: float, att_db: float) -> list:
    """The harmonics worth a notch (module docstring), in increasing order."""
    usable = [ln for ln in lines if ln.freq_hz < HARMONIC_MAX_FRACTION * rate_hz]
    if not usable:
        return []
    after = {ln.harmonic: ln.amp_rad_s * abs(lpf_response(ln.freq_hz, cutoff_hz, rate_hz))
             for ln in usable}
    floor = max(after.values()) * 10.0 ** (-att_db / 20.0)
    return sorted(k for k, a in after.items() if a >= floor)


def _mode(ev: NotchEvidence, asked: int | None) -> int:
    if asked is None:
        return MODE_ESC if ev.esc else MODE_THROTTLE
    if asked == MODE_ESC and not ev.esc:
        raise NotchProposalError("--mode 3 needs ESC telemetry in the log (/esc): fly a "
                                 "scenario with [esc] telemetry_hz, or use --mode 1")
    if asked not in (MODE_THROTTLE, MODE_ESC):
        raise NotchProposalError(f"--mode {asked}: tune notch sets up MODE 1 (throttle) or "
                                 "3 (ESC telemetry)")
    return asked


def _centre(ev: NotchEvidence, mode: int) -> tuple[float, float | None, str, str]:
    """(FREQ, REF, why FREQ, why REF) for the mode."""
    f1 = ev.fundamental_hz
    if mode == MODE_THROTTLE:
        if ev.hover_throttle is None or not ev.hover_throttle > 0:
            raise NotchProposalError("MODE 1 needs the hover throttle (/fc/status) in the "
                                     "log; pass the log of a silbridge flight")
        return (f1, ev.hover_throttle, f"rotor frequency at hover ({ev.fundamental_source})",
                "hover throttle (mixer throttle, fraction of the PWM range)")
    low = ev.lowest_hz if ev.lowest_hz is not None else f1
    freq = max(min(low, f1), ev.gyro_filter_hz)
    return (freq, 1.0, "lowest airborne rotor frequency (the floor of ESC tracking), above "
            "INS_GYRO_FILTER", "1: ESC telemetry gives the rotor frequency unscaled")


def propose(ev: NotchEvidence, att_db: float, mode: int | None = None) -> NotchProposal:
    """The notch and gyro filter for this evidence (module docstring)."""
    mode = _mode(ev, mode)
    freq, ref, why_freq, why_ref = _centre(ev, mode)
    # The notch must also cover how far the motors sit apart (one centre for all four).
    # The octave-width design needs BW < 2 FREQ; at BW = FREQ, Q is already 2/3.
    bw = min(max(BW_OVER_FREQ * freq, 2.0 * ev.spread_hz), freq)
    edge = freq - 0.5 * bw
    gyro = ev.gyro_filter_hz if ev.gyro_filter_hz < edge else float(math.floor(edge))
    harmonics = significant_harmonics(ev.lines, gyro, ev.imu_rate_hz, att_db)
    if not harmonics:
        raise NotchProposalError("no rotor line stands out of the gyro spectrum: a notch "
                                 "would only add phase lag; nothing proposed")
    mask = sum(1 << (k - 1) for k in harmonics)
    # Constant Q: at the hover centre the bandwidth scales with it.
    design = NotchDesign(center_hz=ev.fundamental_hz, bw_hz=bw * ev.fundamental_hz / freq,
                         att_db=att_db, harmonics=mask)
    values = {"INS_HNTCH_ENABLE": 1, "INS_HNTCH_MODE": mode,
              "INS_HNTCH_FREQ": round(freq, 1), "INS_HNTCH_BW": round(bw, 1),
              "INS_HNTCH_ATT": att_db, "INS_HNTCH_HMNCS": mask,
              "INS_HNTCH_REF": round(ref, 3), "INS_GYRO_FILTER": int(gyro)}
    reasons = {
        "INS_HNTCH_ENABLE": "lines found: " + ", ".join(f"{k}x" for k in harmonics),
        "INS_HNTCH_MODE": ("ESC telemetry in the log" if mode == MODE_ESC
                           else "throttle-based (no ESC telemetry in the log)"),
        "INS_HNTCH_FREQ": why_freq,
        "INS_HNTCH_BW": ("FREQ / 2" if bw == BW_OVER_FREQ * freq
                         else "twice the motors' frequency spread (wider than FREQ / 2)"),
        "INS_HNTCH_ATT": "ArduCopter's default depth",
        "INS_HNTCH_HMNCS": f"harmonics within ATT of the strongest after the low-pass: "
                           f"{harmonics}",
        "INS_HNTCH_REF": why_ref,
        "INS_GYRO_FILTER": ("kept: below the notch's lower -3 dB edge "
                            f"({edge:.1f} Hz)" if gyro == ev.gyro_filter_hz else
                            f"lowered to the notch's lower -3 dB edge ({edge:.1f} Hz)"),
    }
    return NotchProposal(values=values, reasons=reasons, design=design, mode=mode)


def predicted_rms(freq_hz: np.ndarray, psd: np.ndarray, response: np.ndarray,
                  band_hz: tuple[float, float]) -> np.ndarray:
    """RMS per axis over band_hz of a raw PSD (n_bins, n_axes) through a filter response."""
    keep = (freq_hz >= band_hz[0]) & (freq_hz <= band_hz[1])
    df = float(freq_hz[1] - freq_hz[0])
    gain2 = np.abs(response[keep]) ** 2
    return np.sqrt((psd[keep] * gain2[:, None]).sum(axis=0) * df)
