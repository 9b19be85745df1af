"""RC input parameters act on the flying vehicle (lockstep, real JSBSim physics, the C core):
the flight-mode switch (FLTMODE_CH, FLTMODE1..6), the throttle failsafe (FS_THR_ENABLE,
FS_THR_VALUE) and the stick calibration (RCn_*, RCMAP_*), all through RC_CHANNELS_OVERRIDE
as the vehicle receives it (rc_override on the vehicle thread)."""

from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.fc_sil.pilot import PilotInput  # noqa: E402
from silbridge.fc_sil.rc_input import ModeSwitch, RcConfig, switch_position  # noqa: E402
from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402

ACCEPTED = 0        # MAV_RESULT_ACCEPTED
NO = 65535          # RC_CHANNELS_OVERRIDE: leave the channel as it is


def _rc(ch3=NO, ch6=NO, ch8=NO):
    chans = [NO] * 18
    chans[2], chans[5], chans[7] = ch3, ch6, ch8
    return tuple(chans)


def _hover_alt_hold_then(after, duration_s, params):
    """GUIDED take-off to 8 m, then ALT_HOLD with the throttle stick centred by RC override."""
    st = {"modes": []}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(8.0)
        if t > 11 and "ah" not in st:
            st["ah"] = v.set_mode(CopterMode.ALT_HOLD)
        if "ah" in st:
            after(f, st)
            st["modes"].append(v.mode.name)

    f, res = fly_scripted(script, duration_s=duration_s, params=params)
    return f, res, st


@pytest.mark.parametrize("enable, expect_failsafe", [(1, True), (0, False)])
def test_throttle_below_fs_thr_value_is_a_radio_failsafe_unless_disabled(enable,
                                                                           expect_failsafe):
    def after(f, st):
        # centred throttle (hold), then a receiver's failsafe PWM (950 < FS_THR_VALUE 975)
        f.v.rc_override(_rc(ch3=1500 if f.t_s < 13 else 950))

    f, res, st = _hover_alt_hold_then(after, 15, {"FS_THR_ENABLE": enable})
    assert st["ah"][0] == ACCEPTED
    fs = any(m[2] == "Radio Failsafe" for m in f.v.messages)
    assert fs == expect_failsafe
    assert ("RTL" in st["modes"]) == expect_failsafe
    if not expect_failsafe:
        assert st["modes"][-1] == "ALT_HOLD"
    assert not res.crashed


def test_mode_switch_selects_fltmode_positions_in_flight():
    # channel 8 as the mode switch; position 2 = LOITER, position 5 = ALT_HOLD
    params = {"FLTMODE_CH": 8, "FLTMODE3": CopterMode.LOITER, "FLTMODE6": CopterMode.ALT_HOLD}

    def after(f, st):
        t = f.t_s
        pwm = NO if t < 12 else 1425 if t < 14 else 1900
        f.v.rc_override(_rc(ch3=1500, ch8=pwm))

    f, res, st = _hover_alt_hold_then(after, 16, params)
    seq = [m for i, m in enumerate(st["modes"]) if i == 0 or m != st["modes"][i - 1]]
    assert seq == ["ALT_HOLD", "LOITER", "ALT_HOLD"], seq
    assert not res.crashed


def test_calibration_and_rcmap_shape_the_sticks():
    get = {f"RC{c}_{k}": v for c in range(1, 17)
           for k, v in (("MIN", 1100), ("MAX", 1900), ("TRIM", 1500), ("DZ", 0), ("REVERSED", 0))}
    get.update({"RCMAP_ROLL": 1, "RCMAP_PITCH": 2, "RCMAP_THROTTLE": 6, "RCMAP_YAW": 4,
                "FLTMODE_CH": 5, "FS_THR_ENABLE": 1, "FS_THR_VALUE": 975,
                **{f"FLTMODE{i}": 0 for i in range(1, 7)},
                "RC1_DZ": 20, "RC4_REVERSED": 1})
    p = PilotInput(clock=lambda: 0.0)
    p.configure(RcConfig.from_params(get.__getitem__))
    p.rc_override((1900, 1100, 2000, 1700, 0, 1500) + (0,) * 12)
    # roll: full at MAX; pitch: full forward at MIN; throttle from channel 6 (RCMAP), ch3 unused
    assert (p.roll, p.pitch) == (1.0, -1.0)
    assert p.throttle == pytest.approx(0.5)
    assert p.yaw == pytest.approx(-0.5)                 # RC4 reversed
    p.rc_override((1510, 0, 0, 0, 0, 1100) + (0,) * 12)
    assert p.roll == 0.0 and p.throttle == 0.0           # inside RC1's dead zone; MIN = bottom
    p.rc_override((1530, 0, 0, 0, 0, 0) + (0,) * 12)
    assert p.roll == pytest.approx(10 / 380)             # (1530 - 1520) / (1900 - 1520)


def test_mode_switch_debounces_and_ignores_invalid_pwm():
    assert [switch_position(u) for u in (1000, 1230, 1231, 1490, 1620, 1749, 1750, 2100)] == \
        [0, 0, 1, 2, 3, 4, 5, 5]
    assert switch_position(700) is None and switch_position(2300) is None
    cfg = RcConfig(mode_ch=5, modes=(0, 2, 5, 6, 9, 16))
    sw = ModeSwitch()
    ch = [1500] * 16
    ch[4] = 1300
    fresh = lambda i: True  # noqa: E731
    assert sw.update(cfg, ch, fresh, 0.0) is None        # first sight: debounce starts
    assert sw.update(cfg, ch, fresh, 0.1) is None
    assert sw.update(cfg, ch, fresh, 0.25) == 2          # held 0.2 s: position 1 -> FLTMODE2
    assert sw.update(cfg, ch, fresh, 0.5) is None        # no repeat while it stays
    ch[4] = 1800
    assert sw.update(cfg, ch, lambda i: False, 1.0) is None   # channel not from the pilot
    assert sw.update(cfg, ch, fresh, 1.0) is None
    ch[4] = 1300                                          # a glitch shorter than 0.2 s
    assert sw.update(cfg, ch, fresh, 1.1) is None
    ch[4] = 1800
    assert sw.update(cfg, ch, fresh, 1.15) is None
    assert sw.update(cfg, ch, fresh, 1.36) == 16          # position 5 -> FLTMODE6
