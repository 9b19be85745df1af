"""Our FC's estimator failsafes as ArduCopter 4.6 has them (docs/reference/failsafes.md):
GNSS glitch rejection, the EKF failsafe on GNSS loss, EKF_STATUS_REPORT's ratios and flags.

Lockstep flights of the real vehicle on the real simulator; the faults come from the bridge's
fault engine (sim.faults.inject), switched from the script at a sim time, as MAVLink's
INJECT_FAILURE reaches it."""

from __future__ import annotations

import math
import os
import sys

from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from vehicle_harness import fly_scripted  # noqa: E402

from silbridge.fc_sil.innov_ratios import EKF_GPS_GLITCHING  # noqa: E402
from silbridge.mavlink.gcs.vehicle_api import CopterMode  # noqa: E402

T_FAULT = 12.0


def _loiter_with_fault(unit, ftype, params, duration_s, flight_s, *, fc_params=None,
                       mode=CopterMode.LOITER, every=None):
    """Take off to 10 m in GUIDED, switch to `mode` at 10 s, fault from T_FAULT for
    duration_s; `every(f, st)` runs after each outer step."""
    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(10.0)
        if t > 10 and "mode" not in st:
            st["mode"] = v.set_mode(mode)
            st["hold_ne"] = f.truth_ne_m()
        if t > T_FAULT and "on" not in st:
            st["on"] = True
            f.sim.faults.inject(unit, ftype, 1, params, True, v.sim_ns)
        if t > T_FAULT + duration_s and "off" not in st:
            st["off"] = True
            f.sim.faults.inject(unit, ftype, 1, params, False, v.sim_ns)
        if every is not None:
            every(f, st)

    f, res = fly_scripted(script, duration_s=flight_s, params=fc_params)
    return f, res, st


def _texts(f):
    return [(t / 1e9, sev, text) for t, sev, text in f.v.messages]


def test_a_30_m_gnss_glitch_in_loiter_is_rejected_and_the_position_held():
    def every(f, st):
        if st.get("on") and not st.get("off"):
            n, e = f.truth_ne_m()
            h = st["hold_ne"]
            st["dev"] = max(st.get("dev", 0.0), math.hypot(n - h[0], e - h[1]))
            snap = f.v.snapshot()
            st["ratio"] = max(st.get("ratio", 0.0), snap.ekf_pos_h_var)
            st["flags"] = st.get("flags", 0) | snap.ekf_flags

    f, res, st = _loiter_with_fault("gnss", "glitch", {"offset_m": [30.0, 0.0, 0.0]}, 5.0, 30.0,
                                    every=every)
    assert st["mode"] == (mav.MAV_RESULT_ACCEPTED, None)
    assert st["dev"] < 3.0                    # the vehicle did not chase the jump
    assert st["ratio"] > 1.0                  # EKF_STATUS_REPORT shows the rejected fixes
    assert st["flags"] & EKF_GPS_GLITCHING
    texts = _texts(f)
    assert any(s == "GPS Glitch or Compass error" and sev == mav.MAV_SEVERITY_CRITICAL
               and T_FAULT < t < T_FAULT + 2.0 for t, sev, s in texts)
    assert not any(s.startswith("EKF") for _, _, s in texts)   # a glitch is not an EKF failure
    # cleared after 10 s of passing fixes (EKF3 calcGpsGoodForFlight)
    assert any(s == "Glitch cleared" and t > T_FAULT + 5.0 + 10.0 for t, _, s in texts)
    assert f.v.mode.number == CopterMode.LOITER and f.v.failsafe.ratios.pos < 1.0
    assert not res.crashed


def test_a_glitch_longer_than_the_retry_time_resets_the_estimate_to_gnss():
    # EKF3: no position fused for 10 s while GNSS velocity still fuses -> reset to the fix
    f, res, st = _loiter_with_fault("gnss", "glitch", {"offset_m": [30.0, 0.0, 0.0]}, 30.0, 26.0)
    est_n = f.v.est.pos_ne_m[0]
    true_n = f.truth_ne_m()[0]
    assert f.v.est.gate.resets >= 1
    assert abs(est_n - (true_n + 30.0)) < 4.0     # the estimate now sits on the glitched fix
    assert not any(s.startswith("EKF Failsafe") for _, _, s in _texts(f))
    assert not res.crashed


def test_gnss_loss_in_loiter_triggers_the_ekf_failsafe_which_lands_and_clears():
    def every(f, st):
        if st.get("on") and "t_fs" not in st and f.v.failsafe.ekf.failsafe:
            st["t_fs"] = f.t_s
            st["alt_fs"] = f.truth_agl_m()
        if "t_fs" in st:
            # ArduCopter's set_mode_land_with_pause: the failsafe's LAND holds 4 s, then descends
            dt = f.t_s - st["t_fs"]
            if dt < 3.5:
                st["pause_drop"] = max(st.get("pause_drop", 0.0), st["alt_fs"] - f.truth_agl_m())
            elif dt > 7.0 and "alt_7s" not in st:
                st["alt_7s"] = f.truth_agl_m()

    f, res, st = _loiter_with_fault("gnss", "off", {}, 12.0, 28.0, every=every)
    texts = _texts(f)
    changed = [t for t, sev, s in texts if s == "EKF Failsafe: changed to LAND Mode"]
    assert changed and any(s == "EKF variance" for _, _, s in texts)
    # the estimate dead-reckons for 7 s (EKF3 posRetryTimeNoVel) before the 1 s count starts
    assert st["t_fs"] - T_FAULT > 7.0
    assert f.v.mode.number == CopterMode.LAND      # a failsafe's LAND stays LAND
    assert st["pause_drop"] < 0.5                  # held its altitude through the pause
    assert st["alt_fs"] - st["alt_7s"] > 1.0       # then descended
    assert any(s == "EKF Failsafe Cleared" and t > T_FAULT + 12.0 for t, _, s in texts)
    assert not res.crashed


def test_fs_ekf_action_2_switches_to_alt_hold():
    f, res, st = _loiter_with_fault("gnss", "off", {}, 30.0, 22.0,
                                    fc_params={"FS_EKF_ACTION": 2})
    assert f.v.mode.number == CopterMode.ALT_HOLD
    assert any(s == "EKF Failsafe: changed to ALT_HOLD Mode" for _, _, s in _texts(f))
    assert not res.crashed


def test_the_ekf_failsafe_leaves_a_mode_without_position_alone():
    # ArduCopter: FS_EKF_ACTION 1 acts only in modes that need position
    f, res, st = _loiter_with_fault("gnss", "off", {}, 30.0, 22.0, mode=CopterMode.ALT_HOLD)
    assert f.v.failsafe.ekf.failsafe
    assert f.v.mode.number == CopterMode.ALT_HOLD
    texts = _texts(f)
    assert any(s == "EKF variance" for _, _, s in texts)
    assert not any(s.startswith("EKF Failsafe:") for _, _, s in texts)
    assert not res.crashed


def test_glitch_hysteresis_starts_when_the_estimate_is_valid_at_its_first_update():
    """A loaded host can hand the FC a valid estimate before its first failsafe check: the
    hysteresis starts its clocks there instead of subtracting from "never" (it once raised
    TypeError and took the FC down)."""
    from types import SimpleNamespace

    from silbridge.fc_sil.innov_ratios import InnovationRatios

    r = InnovationRatios()
    v = SimpleNamespace(sim_ns=5_000_000_000, est=SimpleNamespace(valid=True))
    r._glitch_hysteresis(v)
    assert not r.gps_glitching
    r.pos = 10.0                                   # far outside the gate from now on
    for k in range(1, 60):
        v.sim_ns = 5_000_000_000 + k * 100_000_000
        r._glitch_hysteresis(v)
    assert r.gps_glitching                          # and the clock it started flags it
