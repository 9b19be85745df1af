"""What the in-flight FFT tells the ground station, worded as ArduCopter 4.6 words it.

- "FFT: calibrated 1.0KHz/15.6Hz/187.5Hz" (INFO), once the FFT has learned its noise
  reference: the FFT's sample rate, half a bin (its worst frequency error) and the frames
  per second over the three axes (AP_GyroFFT::pre_arm_check, run by ArduCopter's 1 Hz arming
  checks while disarmed; the figures as it computes them, fc_fft_calibration). With bins
  wider than 50 Hz ArduCopter sends "FFT: resolution is %.1fHz, increase length" (WARNING)
  at every check instead, and so does this.
- "Noise 45dB on motor 2 at 81Hz" (WARNING), FFT_OPTIONS bit 1: at 5 Hz while armed, the
  post-filter FFT's SNR at each ESC-reported motor frequency, at most one round every 5 s
  (AP_Vehicle::check_motor_noise; the check is the core's, fc_fft_esc.c).

Both run on the vehicle's outer-loop step, on sim time.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm.records import NS_PER_S

PREARM_PERIOD_NS = NS_PER_S              # ArduCopter's update_arming task: 1 Hz
ESC_CHECK_PERIOD_NS = NS_PER_S // 5      # its check_motor_noise task: 5 Hz (FC_FFT_ESC_CHECK_S)
RESOLUTION_LIMIT_HZ = 50.0               # AP_GyroFFT::pre_arm_check: coarser bins get a warning


def calibrated_text(sample_khz: float, half_bin_hz: float, output_hz: float) -> str:
    return f"FFT: calibrated {sample_khz:.1f}KHz/{half_bin_hz:.1f}Hz/{output_hz:.1f}Hz"


def motor_noise_text(motor: int, snr_db: float, hz: float) -> str:
    return f"Noise {snr_db:.0f}dB on motor {motor} at {hz:.0f}Hz"


class FftNotices:
    """The FFT's STATUSTEXTs; ``check(v)`` once per outer-loop step of a Vehicle."""

    def __init__(self):
        self.calibrated_sent = False
        self._next_prearm_ns: int | None = None
        self._next_esc_ns: int | None = None
        self._last_esc_ns: int | None = None

    def check(self, v) -> None:
        now = v.sim_ns
        if self._next_prearm_ns is None:
            self._next_prearm_ns = self._next_esc_ns = now
        if now >= self._next_prearm_ns:
            self._next_prearm_ns = now + PREARM_PERIOD_NS
            if not v.armed:
                self._prearm(v)
        if now >= self._next_esc_ns:
            self._next_esc_ns = now + ESC_CHECK_PERIOD_NS
            dt_s = 0.0 if self._last_esc_ns is None else (now - self._last_esc_ns) / NS_PER_S
            self._last_esc_ns = now
            for motor, snr_db, hz in v.core.fft_esc_noise(dt_s):
                v.statustext(mav.MAV_SEVERITY_WARNING, motor_noise_text(motor, snr_db, hz))

    def _prearm(self, v) -> None:
        figures = v.core.fft_calibration()
        if figures is None:              # off, or learning its noise again after a restart
            self.calibrated_sent = False
            return
        if self.calibrated_sent:
            return
        sample_khz, half_bin_hz, output_hz = figures
        if 2.0 * half_bin_hz > RESOLUTION_LIMIT_HZ:
            v.statustext(mav.MAV_SEVERITY_WARNING,
                         f"FFT: resolution is {2.0 * half_bin_hz:.1f}Hz, increase length")
            return
        self.calibrated_sent = True
        v.statustext(mav.MAV_SEVERITY_INFO, calibrated_text(sample_khz, half_bin_hz, output_hz))
