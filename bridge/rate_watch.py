"""The real-time rate check as a measurement: report a shortfall, keep flying.

The paper's start-up procedure (section 4.2, step 5) wants IMU and PWM within +-5 % of their
rates. In lockstep they hold by construction; in real time a busy host (a compiler, a browser,
a benchmark beside it) can fall short. Refusing to start then leaves the user with no vehicle
where ArduCopter SITL would run, slower: so the run goes on, and the shortfall is said once
when found, then at most every `report_every_s` of wall time while it lasts (never a line per
window), and counted for the summary's "rates". `--strict-rates` keeps the refusal for the
benchmarks that need exact rates (bridge/bridge_driver.py raises before this is consulted).

Rates are in sim-time Hz (samples per wall second / speed), the unit the check always used.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RateShortfall:
    imu_hz: float
    imu_want_hz: float
    pwm_hz: float
    pwm_want_hz: float
    imu_short: bool
    pwm_short: bool

    def line(self) -> str:
        """The console line (the same figures the refused start-up check printed)."""
        return (f"rates short (slow host; running on, --strict-rates refuses): IMU "
                f"{self.imu_hz:.1f} Hz (want {self.imu_want_hz:g}), PWM {self.pwm_hz:.1f} Hz "
                f"(want {self.pwm_want_hz:g})")

    def statustext(self) -> str:
        """ArduPilot-style, within STATUSTEXT's 50 characters ("SIM:" as its SITL's own)."""
        both = self.imu_short and self.pwm_short
        gap = "<" if both else " < "    # both figures: the compact form keeps the reason
        parts = []
        if self.imu_short:
            parts.append(f"IMU {self.imu_hz:.0f}{'' if both else 'Hz'}{gap}"
                         f"{self.imu_want_hz:.0f}Hz")
        if self.pwm_short:
            parts.append(f"PWM {self.pwm_hz:.0f}{'' if both else 'Hz'}{gap}"
                         f"{self.pwm_want_hz:.0f}Hz")
        text = "SIM: " + ", ".join(parts) + " (slow host)"
        if len(text) > 50:      # never cut a figure: drop the reason first
            text = "SIM: " + ", ".join(parts)
        return text[:50]


class RateWatch:
    """Judges measured rates against the wanted ones and paces the reports.

    Each check window calls judge(); it returns the shortfall to report now, or None
    (rates fine, or a report was made less than report_every_s ago)."""

    def __init__(self, imu_want_hz: float, pwm_want_hz: float, tolerance: float,
                 report_every_s: float = 10.0):
        self.imu_want_hz = imu_want_hz
        self.pwm_want_hz = pwm_want_hz
        self.tolerance = tolerance
        self.report_every_s = report_every_s
        self.degraded = False           # any window (or the whole run) fell short
        self.short_windows = 0
        self.reports = 0
        self._last_report_wall_s: float | None = None

    def shortfall(self, imu_hz: float, pwm_hz: float) -> RateShortfall | None:
        """The shortfall in these rates, None within tolerance. Only a rate BELOW its
        target is a shortfall: above it is a scheduler catching up after a late stretch."""
        imu_short = imu_hz < self.imu_want_hz * (1.0 - self.tolerance)
        pwm_short = pwm_hz < self.pwm_want_hz * (1.0 - self.tolerance)
        if not (imu_short or pwm_short):
            return None
        return RateShortfall(imu_hz, self.imu_want_hz, pwm_hz, self.pwm_want_hz,
                             imu_short, pwm_short)

    def judge(self, imu_hz: float, pwm_hz: float, wall_s: float) -> RateShortfall | None:
        """One window's rates, measured wall_s seconds into the run."""
        short = self.shortfall(imu_hz, pwm_hz)
        if short is None:
            return None
        self.short_windows += 1
        if not self.degraded:
            self.degraded = True
        elif (self._last_report_wall_s is not None
                and wall_s - self._last_report_wall_s < self.report_every_s):
            return None
        self._last_report_wall_s = wall_s
        self.reports += 1
        return short
