"""Pilot input from the GCS: MANUAL_CONTROL and RC_CHANNELS_OVERRIDE, as sticks.

Both arrive on the GCS thread and are handed to the vehicle thread by the server; this
holder keeps the latest sticks with their wall-clock arrival time (a link's age is wall
time, whatever the simulation speed). Sticks are normalised:
  roll  -1..1 (+ right), pitch -1..1 (+ stick back = nose up), yaw -1..1 (+ clockwise),
  throttle 0..1 (0.5 = centre).
MANUAL_CONTROL: x forward (+1000 = stick forward), y right, z throttle 0..1000, r yaw.
RC override: 16 channels; 0 and 65535 leave a channel as it was (UINT16_MAX "ignore" in
MAVLink 2). The sticks come from the channels through the RC calibration and RCMAP_* of
rc_input.py (``configure``; without it channels 1..4 = roll, pitch, throttle, yaw over
1000..2000 us, no dead zone). A low pitch channel is stick forward, as in ArduCopter.
"""

from __future__ import annotations

import time

from .rc_input import N_CHANNELS, RcConfig

RC_MIN_US, RC_MID_US, RC_MAX_US = 1000.0, 1500.0, 2000.0


def _clamp(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


class PilotInput:
    def __init__(self, clock=time.monotonic):
        self.clock = clock
        self.roll = self.pitch = self.yaw = 0.0
        self.throttle = 0.0
        self.t_s: float | None = None           # arrival of the last input (wall clock)
        self.channels_us = [1500, 1500, 1000, 1500] + [1000] * (N_CHANNELS - 4)
        self.overridden = [False] * N_CHANNELS  # channel ever set by RC override
        self.rc = RcConfig()
        self.lost = False                       # an injected RC loss (fault_inject.py)
        self._had_input = False

    def set_lost(self, lost: bool) -> None:
        """An injected receiver loss: input stops arriving, so its age grows and the radio
        failsafe sees what a real loss shows. A vehicle that never had pilot input counts its
        silence from the loss (the receiver was there, now it is not); when the loss ends it
        is back to never having had input."""
        if lost and not self.lost:
            self._had_input = self.t_s is not None
            if self.t_s is None:
                self.t_s = self.clock()
        elif not lost and self.lost and not self._had_input:
            self.t_s = None
        self.lost = lost

    def configure(self, rc: RcConfig) -> None:
        self.rc = rc

    def manual_control(self, x: int, y: int, z: int, r: int) -> None:
        if self.lost:
            return
        # INT16_MAX marks an axis as unused (MAVLink): keep its last value
        if x != 32767:
            self.pitch = -_clamp(x / 1000.0, -1.0, 1.0)
        if y != 32767:
            self.roll = _clamp(y / 1000.0, -1.0, 1.0)
        if z != 32767:
            self.throttle = _clamp(z / 1000.0, 0.0, 1.0)
        if r != 32767:
            self.yaw = _clamp(r / 1000.0, -1.0, 1.0)
        self._mirror_channels()
        self.t_s = self.clock()

    def rc_override(self, channels_us) -> None:
        if self.lost:
            return
        for i, us in enumerate(channels_us[:len(self.channels_us)]):
            if us not in (0, 65535) and RC_MIN_US - 200 <= us <= RC_MAX_US + 200:
                self.channels_us[i] = int(us)
                self.overridden[i] = True
        # low pitch channel = forward = nose down = negative pitch
        self.roll, self.pitch, self.yaw, self.throttle = self.rc.sticks(self.channels_us)
        self.t_s = self.clock()

    def channel_fresh(self, i: int, timeout_s: float) -> bool:
        """Channel i (0-based) came from RC override and the input is not stale."""
        return self.overridden[i] and self.fresh(timeout_s)

    def throttle_pwm(self) -> int | None:
        """PWM of the throttle channel if RC override set it, else None."""
        i = self.rc.throttle_ch - 1
        return self.channels_us[i] if self.overridden[i] else None

    def _mirror_channels(self) -> None:
        """RC_CHANNELS telemetry shows manual-control sticks as the RC values they mean."""
        rc = self.rc
        self.channels_us[rc.roll_ch - 1] = int(RC_MID_US + 500.0 * self.roll)
        self.channels_us[rc.pitch_ch - 1] = int(RC_MID_US + 500.0 * self.pitch)
        self.channels_us[rc.throttle_ch - 1] = int(RC_MIN_US + 1000.0 * self.throttle)
        self.channels_us[rc.yaw_ch - 1] = int(RC_MID_US + 500.0 * self.yaw)

    def age_s(self) -> float | None:
        """Seconds since the last input; None if there never was one."""
        return None if self.t_s is None else self.clock() - self.t_s

    def fresh(self, timeout_s: float) -> bool:
        a = self.age_s()
        return a is not None and a <= timeout_s
