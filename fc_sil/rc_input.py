"""RC input as ArduCopter reads it: calibration, stick mapping and the flight-mode switch.

The vehicle's RC input is RC_CHANNELS_OVERRIDE (pilot.py keeps the latest PWM per channel).
ArduCopter turns those PWM values into sticks with each channel's calibration, and a ground
station's radio-calibration page (QGroundControl's, MAVProxy's `rc` module) writes exactly
these parameters, so they act here as they do there (RC_Channel.cpp of ArduPilot):

* RCn_MIN / RCn_MAX / RCn_TRIM / RCn_DZ / RCn_REVERSED: a stick channel (roll, pitch, yaw) is
  -1..1 about trim with a dead zone of DZ either side, scaled to MIN and MAX separately; the
  throttle channel is 0..1 from MIN + DZ to MAX. Reversed mirrors the channel.
* RCMAP_ROLL / _PITCH / _THROTTLE / _YAW: which channel carries which stick.
* FLTMODE_CH and FLTMODE1..6: the PWM of the mode channel selects one of six positions
  (edges 1230/1360/1490/1620/1749 us, as ArduCopter's 6-position switch and QGC's flight-mode
  page); a position held for SWITCH_DEBOUNCE_S of simulation time (ArduPilot's millis() is sim
  time in SITL) changes the mode once, as a real switch does. PWM outside 800..2200 is ignored.
* FS_THR_ENABLE / FS_THR_VALUE: the radio failsafe (vehicle_nav.py) also triggers when the
  throttle channel's PWM is below FS_THR_VALUE; FS_THR_ENABLE 0 turns the radio failsafe off.
"""

from __future__ import annotations

from dataclasses import dataclass

from silbridge.mavlink.gcs.vehicle_api import CopterMode

N_CHANNELS = 16
MODE_EDGES_US = (1230, 1360, 1490, 1620, 1749)
SWITCH_DEBOUNCE_S = 0.2
PWM_VALID = (800, 2200)   # ArduPilot's RC_MIN_LIMIT_PWM / RC_MAX_LIMIT_PWM (exclusive)

# FS_THR_ENABLE -> mode. SmartRTL and brake are not modelled: their documented fall-backs.
_FS_THR_ACTION = {1: CopterMode.RTL, 2: CopterMode.RTL, 3: CopterMode.LAND, 4: CopterMode.RTL,
                  5: CopterMode.LAND, 6: CopterMode.RTL, 7: CopterMode.LAND}


def _clamp(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


@dataclass(frozen=True)
class ChannelCal:
    min_us: int = 1000
    max_us: int = 2000
    trim_us: int = 1500
    dz_us: int = 0
    reversed: bool = False

    def angle(self, pwm: float) -> float:
        """-1..1 about trim with the dead zone (ArduPilot pwm_to_angle_dz_trim, normalised)."""
        r = _clamp(pwm, self.min_us, self.max_us)
        hi, lo = self.trim_us + self.dz_us, self.trim_us - self.dz_us
        if r > hi and self.max_us != hi:
            v = (r - hi) / (self.max_us - hi)
        elif r < lo and lo != self.min_us:
            v = (r - lo) / (lo - self.min_us)
        else:
            v = 0.0
        return _clamp(-v if self.reversed else v, -1.0, 1.0)

    def range(self, pwm: float) -> float:
        """0..1 from MIN + DZ to MAX (ArduPilot pwm_to_range_dz, normalised)."""
        r = _clamp(pwm, self.min_us, self.max_us)
        if self.reversed:
            r = self.max_us - (r - self.min_us)
        low = self.min_us + self.dz_us
        if r <= low or self.max_us <= low:
            return 0.0
        return _clamp((r - low) / (self.max_us - low), 0.0, 1.0)


@dataclass(frozen=True)
class RcConfig:
    cal: tuple[ChannelCal, ...] = (ChannelCal(),) * N_CHANNELS
    roll_ch: int = 1          # RCMAP_*: 1-based channel numbers
    pitch_ch: int = 2
    throttle_ch: int = 3
    yaw_ch: int = 4
    mode_ch: int = 0          # FLTMODE_CH; 0 = no mode switch
    modes: tuple[int, ...] = (CopterMode.STABILIZE,) * 6
    fs_thr_enable: int = 1
    fs_thr_value_us: int = 975

    @classmethod
    def from_params(cls, get) -> "RcConfig":
        cal = tuple(ChannelCal(int(get(f"RC{c}_MIN")), int(get(f"RC{c}_MAX")),
                               int(get(f"RC{c}_TRIM")), int(get(f"RC{c}_DZ")),
                               bool(get(f"RC{c}_REVERSED")))
                    for c in range(1, N_CHANNELS + 1))
        return cls(cal=cal, roll_ch=int(get("RCMAP_ROLL")), pitch_ch=int(get("RCMAP_PITCH")),
                   throttle_ch=int(get("RCMAP_THROTTLE")), yaw_ch=int(get("RCMAP_YAW")),
                   mode_ch=int(get("FLTMODE_CH")),
                   modes=tuple(int(get(f"FLTMODE{i}")) for i in range(1, 7)),
                   fs_thr_enable=int(get("FS_THR_ENABLE")),
                   fs_thr_value_us=int(get("FS_THR_VALUE")))

    def sticks(self, channels_us) -> tuple[float, float, float, float]:
        """(roll, pitch, yaw -1..1, throttle 0..1) from channel PWM values."""
        def ch(c):
            return self.cal[c - 1], channels_us[c - 1]
        cr, pr = ch(self.roll_ch)
        cp, pp = ch(self.pitch_ch)
        cy, py = ch(self.yaw_ch)
        ct, pt = ch(self.throttle_ch)
        return cr.angle(pr), cp.angle(pp), cy.angle(py), ct.range(pt)

    def fs_thr_action(self) -> int | None:
        """The mode the radio failsafe selects; None when FS_THR_ENABLE is 0."""
        return _FS_THR_ACTION.get(self.fs_thr_enable) if self.fs_thr_enable else None


def switch_position(pwm_us: int) -> int | None:
    """0..5 for a valid PWM, None outside ArduPilot's valid range."""
    if not PWM_VALID[0] < pwm_us < PWM_VALID[1]:
        return None
    for pos, edge in enumerate(MODE_EDGES_US):
        if pwm_us <= edge:
            return pos
    return 5


class ModeSwitch:
    """ArduPilot's debounced 6-position mode switch; ``update`` returns a mode to select."""

    def __init__(self):
        self.position: int | None = None    # established position (None: none yet)
        self._candidate: int | None = None
        self._since_s = 0.0

    def update(self, cfg: RcConfig, channels_us, channel_fresh, now_s: float) -> int | None:
        c = cfg.mode_ch
        if not 1 <= c <= N_CHANNELS or not channel_fresh(c - 1):
            return None
        pos = switch_position(int(channels_us[c - 1]))
        if pos is None:
            return None
        if pos == self.position:
            self._candidate = pos
            return None
        if pos != self._candidate:
            self._candidate, self._since_s = pos, now_s
            return None
        if now_s - self._since_s < SWITCH_DEBOUNCE_S:
            return None
        self.position = pos
        return cfg.modes[pos]
