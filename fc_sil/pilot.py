"""Pilot input from the GCS: MANUAL_CONTROL and RC_CHANNELS_OVERRIDE, as sticks.

Both arrive on the GCS thread and are handed to the vehicle thread by the server; this
holder keeps the latest sticks with their wall-clock arrival time (a link's age is wall
time, whatever the simulation speed). Sticks are normalised:
  roll  -1..1 (+ right), pitch -1..1 (+ stick back = nose up), yaw -1..1 (+ clockwise),
  throttle 0..1 (0.5 = centre).
MANUAL_CONTROL: x forward (+1000 = stick forward), y right, z throttle 0..1000, r yaw.
RC override: channels 1..4 = roll, pitch, throttle, yaw (ArduCopter's default RCMAP), PWM
1000..2000 us; 0 and 65535 leave a channel as it was (UINT16_MAX "ignore" in MAVLink 2).
ArduCopter's RC2 is reversed: a low pitch channel is stick forward.
"""

from __future__ import annotations

import time

RC_MIN_US, RC_MID_US, RC_MAX_US = 1000.0, 1500.0, 2000.0


def _clamp(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


class PilotInput:
    def __init__(self, clock=time.monotonic):
        self.clock = clock
        self.roll = self.pitch = self.yaw = 0.0
        self.throttle = 0.0
        self.t_s: float | None = None           # arrival of the last input (wall clock)
        self.channels_us = [1500, 1500, 1000, 1500, 1000, 1000, 1000, 1000]

    def manual_control(self, x: int, y: int, z: int, r: int) -> None:
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
        def norm(us):
            return _clamp((us - RC_MID_US) / (RC_MAX_US - RC_MID_US), -1.0, 1.0)

        for i, us in enumerate(channels_us[:len(self.channels_us)]):
            if us not in (0, 65535) and RC_MIN_US - 200 <= us <= RC_MAX_US + 200:
                self.channels_us[i] = int(us)
        ch = self.channels_us
        self.roll = norm(ch[0])
        self.pitch = norm(ch[1])                # low = forward = nose down = negative
        self.throttle = _clamp((ch[2] - RC_MIN_US) / (RC_MAX_US - RC_MIN_US), 0.0, 1.0)
        self.yaw = norm(ch[3])
        self.t_s = self.clock()

    def _mirror_channels(self) -> None:
        """RC_CHANNELS telemetry shows manual-control sticks as the RC values they mean."""
        self.channels_us[0] = int(RC_MID_US + 500.0 * self.roll)
        self.channels_us[1] = int(RC_MID_US + 500.0 * self.pitch)
        self.channels_us[2] = int(RC_MIN_US + 1000.0 * self.throttle)
        self.channels_us[3] = int(RC_MID_US + 500.0 * self.yaw)

    def age_s(self) -> float | None:
        """Seconds since the last input; None if there never was one."""
        return None if self.t_s is None else self.clock() - self.t_s

    def fresh(self, timeout_s: float) -> bool:
        a = self.age_s()
        return a is not None and a <= timeout_s
