"""Thrust-loss, vibration and crash checks of our FC, as ArduCopter 4.6 has them
(docs/reference/failsafes.md).

Thrust loss and vibration: lockstep flights of the real vehicle with the bridge's motor and
accelerometer faults. The crash check acts only after an impact, and the bridge ends a run
at the impact (its crash verdict), so no flight reaches the 2 s the check waits: its rule is
pinned on the check itself with the vehicle state a crashed copter presents."""

from __future__ import annotations

import math
import os
import sys
from types import SimpleNamespace

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from test_failsafe_estimator import T_FAULT, _loiter_with_fault, _texts  # noqa: E402
from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.fc_sil.crash_check import CrashCheck  # noqa: E402
from silbridge.fc_sil.params import PARAMS  # noqa: E402
from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402


def test_a_motor_losing_most_of_its_thrust_is_reported_by_number():
    f, res, st = _motor_loss(2, 0.3, {})
    texts = _texts(f)
    hits = [(t, sev) for t, sev, s in texts if s == "Potential Thrust Loss (2)"]
    assert hits and hits[0][1] == mav.MAV_SEVERITY_EMERGENCY and hits[0][0] > T_FAULT + 1.0
    assert len(hits) == 1                      # the boost latches: one warning
    assert not any("Thrust Loss (1)" in s or "Thrust Loss (3)" in s or "Thrust Loss (4)" in s
                   for _, _, s in texts)


def test_flight_options_bit_0_turns_the_thrust_loss_check_off():
    f, res, st = _motor_loss(2, 0.3, {"FLIGHT_OPTIONS": 1})
    assert not any("Thrust Loss" in s for _, _, s in _texts(f))


def test_a_yaw_integrator_held_at_its_limit_warns_of_yaw_imbalance():
    # motor 1 keeps 60 % of its thrust and torque: the yaw I term winds up to a small IMAX
    f, res, st = _loiter_with_fault("motor", "thrust_loss", {"remaining": 0.6}, 60.0, 30.0,
                                    fc_params={"ATC_RAT_YAW_IMAX": 0.08})
    warns = [(t, sev, s) for t, sev, s in _texts(f) if s.startswith("Yaw Imbalance ")]
    assert warns and all(sev == mav.MAV_SEVERITY_EMERGENCY for _, sev, _ in warns)
    assert all(b[0] - a[0] > 10.0 for a, b in zip(warns, warns[1:]))   # at most every 10 s
    assert not res.crashed


def _motor_loss(motor: int, remaining: float, fc_params: dict):
    """Hover in LOITER at 10 m; from T_FAULT one motor keeps `remaining` of its thrust. The
    vehicle sinks at full throttle and hits the ground: the bridge ends the run there."""
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(10.0)
        if t > 10 and "mode" not in st:
            st["mode"] = v.set_mode(CopterMode.LOITER)
        if t > T_FAULT and "on" not in st:
            st["on"] = True
            f.sim.faults.inject("motor", "thrust_loss", motor, {"remaining": remaining}, True,
                                v.sim_ns)

    f, res = fly_scripted(script, duration_s=16.0, params=fc_params)
    return f, res, st


def _vibe_flight(enable: int):
    def every(f, st):
        if f.v.core.inputs()["vibe_comp"]:
            st["comp"] = True

    # +4 m/s^2 on the accelerometer's z: the vertical estimate believes it is sinking, as
    # aliased vibration makes it believe; the GNSS vertical velocity and the baro disagree
    return _loiter_with_fault("accel", "bias", {"bias": [0.0, 0.0, 4.0]}, 30.0, 18.0,
                              fc_params={"FS_VIBE_ENABLE": enable}, every=every)


def test_accelerometer_aliasing_switches_on_vibration_compensation():
    f, res, st = _vibe_flight(1)
    on = [(t, sev) for t, sev, s in _texts(f) if s == "Vibration compensation ON"]
    assert on and on[0][1] == mav.MAV_SEVERITY_CRITICAL and on[0][0] > T_FAULT + 1.0
    assert st.get("comp")                     # the altitude loop runs its resistant law
    assert not res.crashed


def test_fs_vibe_enable_0_leaves_the_altitude_loop_alone():
    f, res, st = _vibe_flight(0)
    assert not any(s.startswith("Vibration compensation") for _, _, s in _texts(f))
    assert not st.get("comp")


# ---- crash check: the rule on the check itself ------------------------------------------------

class _CrashedCopter:
    """What a copter lying on its side after an impact presents to the crash check: armed,
    not landed (a position mode keeps asking for thrust), still, rolled 80 deg against a level
    target."""

    def __init__(self, roll_deg: float = 80.0, crash_check: int = 1):
        self.sim_ns = 0
        self.armed, self.airborne = True, True
        self.euler_rad = (math.radians(roll_deg), 0.0, 0.0)
        self.status = {"att_target_rad": np.zeros(3, np.float32)}
        self.est = SimpleNamespace(vel_ne_m_s=[0.0, 0.0], acc_ned_m_s2=(0.0, 0.0, 0.0))
        self.climb_m_s = 0.0
        defaults = {p.name: p.default for p in PARAMS}
        defaults["FS_CRASH_CHECK"] = crash_check
        self.store = SimpleNamespace(host=defaults.__getitem__)
        self.messages = []

    def statustext(self, sev, text):
        self.messages.append((self.sim_ns, sev, text))

    def failsafe_disarm(self):
        self.armed = False


def _run(copter, seconds: float):
    check = CrashCheck()
    for k in range(int(seconds * 50) + 1):
        copter.sim_ns = k * 20_000_000
        check.check(copter)
    return check


def test_the_crash_check_disarms_after_two_seconds_on_its_side():
    c = _CrashedCopter()
    _run(c, 1.9)
    assert c.armed
    _run(c, 2.1)
    assert not c.armed
    sev, text = c.messages[0][1:]
    assert sev == mav.MAV_SEVERITY_EMERGENCY
    assert text == "Crash: Disarming: AngErr=80>30, Accel=0.0<3.0"


def test_the_crash_check_spares_a_level_or_moving_copter_and_obeys_fs_crash_check():
    level = _CrashedCopter(roll_deg=10.0)           # within 15 deg of level
    _run(level, 5.0)
    off = _CrashedCopter(crash_check=0)
    _run(off, 5.0)
    moving = _CrashedCopter()
    moving.est.vel_ne_m_s = [12.0, 0.0]             # 10 m/s or faster: not crashed
    _run(moving, 5.0)
    assert level.armed and off.armed and moving.armed
