"""Pre-arm checks, GCS-only control, auto-disarm and failsafes of the MAVLink vehicle
(lockstep flights on the real simulator; sensor loss by dropping a stream before the core)."""

from __future__ import annotations

import os
import sys

from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import DroppingCore, fly_scripted  # noqa: E402

from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402
from silbridge.shm.records import Kind  # noqa: E402

ACCEPTED, FAILED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_FAILED


def test_starts_disarmed_on_the_ground_and_ignores_scenario_setpoints():
    # S1's script commands a take-off to 10 m at once; under MAVLink control nothing happens
    f, res = fly_scripted(lambda f: None, duration_s=8)
    assert not f.v.armed
    assert max(s["agl"] for s in f.log) < 0.05
    assert f.v.mode.number == CopterMode.STABILIZE
    assert f.v.core.inputs()["armed"] is False


def test_prearm_checks_name_the_failing_check():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if "early" not in st:
            st["early"] = v.arm(False)                 # estimator has not run yet
        if t > 3 and "land" not in st:
            v.set_mode(CopterMode.LAND)
            st["land"] = v.arm(False)
            v.set_mode(CopterMode.STABILIZE)
            v.manual_control(0, 0, 600, 0, 0)          # throttle up
            st["thr"] = v.arm(False)
            v.manual_control(0, 0, 0, 0, 0)
            st["ok"] = v.arm(False)
            st["disarm"] = v.disarm(False)
            st["forced"] = None

    fly_scripted(script, duration_s=4)
    assert st["early"][0] == FAILED and st["early"][1].startswith("PreArm:")
    assert st["land"] == (FAILED, "Arm: Mode LAND not armable")
    assert st["thr"] == (FAILED, "Arm: Throttle too high")
    assert st["ok"] == (ACCEPTED, None)
    assert st["disarm"] == (ACCEPTED, None)


def test_gps_needed_for_position_modes():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "r" not in st:
            st["r"] = v.set_mode(CopterMode.GUIDED)
            st["alt_hold"] = v.set_mode(CopterMode.ALT_HOLD)
            st["arm"] = v.arm(False)

    fly_scripted(script, duration_s=4, core=DroppingCore(Kind.GNSS, 0.0))
    assert st["r"][0] == FAILED and "requires position" in st["r"][1]
    assert st["alt_hold"] == (ACCEPTED, None)
    assert st["arm"] == (ACCEPTED, None)       # ALT_HOLD does not need GPS


def test_disarm_delay_disarms_after_landing_idle():
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "arm" not in st:
            v.set_mode(CopterMode.GUIDED)
            st["arm"] = v.arm(False)
            st["t_arm"] = t
        if "arm" in st and not v.armed and "t_off" not in st:
            st["t_off"] = t

    f, _ = fly_scripted(script, duration_s=12, params={"DISARM_DELAY": 5})
    assert st["arm"] == (ACCEPTED, None)
    assert 4.9 < st["t_off"] - st["t_arm"] < 5.5
    assert any("auto" in m[2] for m in f.v.messages)


def _hover_then(script_after, duration_s, **kw):
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(8.0)
        script_after(f, st)

    f, res = fly_scripted(script, duration_s=duration_s, **kw)
    return f, res, st


def _small_pack() -> str:
    import tempfile
    p = os.path.join(tempfile.mkdtemp(), "low.toml")
    with open(p, "w") as fh:
        fh.write('name = "low"\nseed = 1\nduration_s = 60.0\n\n[battery]\ninitial_soc = 0.07\n')
    return p


def test_low_battery_triggers_rtl():
    def after(f, st):
        st.setdefault("modes", set()).add(f.v.mode.name)

    # the bridge's pack at 7 % charge (of 3300 mAh: 230 mAh), low at 150 mAh left; hover
    # draws ~10 A (2.8 mAh/s), so it crosses in ~30 s
    f, res, st = _hover_then(after, 50, scenario=_small_pack(), params={"BATT_LOW_MAH": 150,
                                                                        "RTL_LOIT_TIME": 0})
    assert "RTL" in st["modes"]
    assert any("Battery 1 is low" in m[2] for m in f.v.messages)
    assert not res.crashed


def test_baro_loss_in_flight_lands():
    f, res, st = _hover_then(lambda f, st: None, 22, core=DroppingCore(Kind.BARO, 15.0))
    assert f.v.mode.number == CopterMode.LAND
    assert any("Baro data lost" in m[2] for m in f.v.messages)
    assert not res.crashed


def test_imu_loss_stops_the_motors_with_a_statustext():
    f, res, st = _hover_then(lambda f, st: None, 17, core=DroppingCore(Kind.IMU, 15.0))
    assert not f.v.armed
    assert not f.v.core.inputs()["armed"]
    assert any("IMU data lost" in m[2] and m[1] == mav.MAV_SEVERITY_CRITICAL
               for m in f.v.messages)


def test_radio_failsafe_when_pilot_input_stops_in_alt_hold():
    import time as _time

    def after(f, st):
        v, t = f.v, f.t_s
        if t > 12 and "ah" not in st:
            st["ah"] = v.set_mode(CopterMode.ALT_HOLD)
            v.manual_control(0, 0, 500, 0, 0)
            # the pilot's link ages in wall time: pretend the last input is 2 s old
            v.pilot.t_s = _time.monotonic() - 2.0
        if "ah" in st:
            st.setdefault("modes", []).append(v.mode.name)

    f, res, st = _hover_then(after, 14)
    assert st["ah"] == (ACCEPTED, None)
    assert "RTL" in st["modes"]
    assert any(m[2] == "Radio Failsafe" for m in f.v.messages)


def test_gps_loss_in_a_position_mode_lands():
    # ArduCopter's way: the estimate times out (7 s without GNSS), the EKF failsafe lands
    f, res, st = _hover_then(lambda f, st: None, 22, core=DroppingCore(Kind.GNSS, 12.0))
    assert f.v.mode.number == CopterMode.LAND
    assert any(m[2] == "EKF Failsafe: changed to LAND Mode" for m in f.v.messages)
    assert not res.crashed
