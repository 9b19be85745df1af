"""The failure benchmark (`silbridge bench --suite failures`, tools/benchmark/failures/).

- F1..F12 load, each fault is in the catalog, and each plan's scenario (physics.toml plus
  its [plan.physics] keys and [[failure]] entries) passes the scenario schema.
- ArduCopter's translation: a 30 m GNSS glitch north becomes the SIM_GPS_GLITCH_X degrees
  that put the reported position 30 m north in the ground-truth frame; every catalog fault
  has a route to every autopilot.
- The scores on synthetic timelines and trajectories whose answers are known: the first
  alert or failsafe mode change is the detection (an INFO text is not), a hold at the end
  of a mission is not an action, a fall is a crash and a slow touchdown a landing, a crash
  check's disarm is on the ground.
- Real flights: our FC (always) and ArduCopter 4.6 (when SILBRIDGE_ARDUCOPTER names it)
  fly F2 (GNSS off in position hold) and F8 (battery capacity loss in AUTO); ArduCopter's
  EKF failsafe lands (LAND) and its battery failsafe returns (RTL) with the BATT_*
  thresholds every autopilot gets; our FC's rows for the same scenarios are asserted to do
  the same.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.shm import fault_catalog as cat
from silbridge.tools.benchmark.failures import translate
from silbridge.tools.benchmark.failures.campaign import run_one
from silbridge.tools.benchmark.failures.plans import ALT_M, PLANS, write_scenario
from silbridge.tools.benchmark.failures.scoring import (Truth, detection, disarm,
                                                        disarm_time, first_action, outcome)
from silbridge.tools.benchmark.failures.watch import Timeline
from silbridge.tools.benchmark.nav.geo import latlon_e7_to_ne

ARDUCOPTER = os.environ.get("SILBRIDGE_ARDUCOPTER")
GUIDED, LAND, AUTO = 4, 9, 3


def test_every_plan_is_a_valid_scenario(tmp_path):
    assert list(PLANS) == [f"F{i}" for i in range(1, 13)]
    units = set()
    for plan in PLANS.values():
        sc = load_scenario(write_scenario(plan, str(tmp_path)), seed=3)
        # the client's own faults (GCS loss) are not the engine's
        assert [f.unit for f in sc.failures] == [f["unit"] for f in plan.engine_failures()]
        # F12's crash does not end the run (the crash check and the disarm come after it)
        assert sc.physics.end_on_crash == (plan.name != "F12")
        units |= set(plan.units)
    # every fault class is flown
    assert units == {u.name for u in cat.UNITS}
    assert translate.route("ours", "rc", "lost").how == translate.FC_SIDE


def test_gnss_glitch_becomes_arducopters_degrees():
    lat, lon = 47.397742, 8.545594
    switches = translate.sim_param_switches("ardupilot", PLANS["F1"], lat)
    (t_on, on), (t_off, off) = switches
    assert (t_on, t_off) == (80.0, 110.0) and off["SIM_GPS_GLITCH_X"] == 0.0
    # SITL adds X to the latitude in degrees: the reported point lies 30 m north of truth.
    lat_e7 = round((lat + on["SIM_GPS_GLITCH_X"]) * 1e7)
    north, east = latlon_e7_to_ne(lat, lon, lat_e7, round(lon * 1e7))
    assert north == pytest.approx(30.0, abs=0.02) and east == pytest.approx(0.0, abs=0.01)


def test_every_catalog_fault_has_a_route_to_every_autopilot():
    for u in cat.UNITS:
        for t in u.types:
            for fc in ("ours", "ardupilot", "px4"):
                r = translate.route(fc, u.name, t.name)
                assert r.how in (translate.BRIDGE, translate.CLIENT, translate.SIM_PARAM,
                                 translate.FC_SIDE, translate.NONE)
                if r.how == translate.SIM_PARAM:
                    assert r.on is not None and r.text
    assert translate.route("ours", "gnss", "glitch").how == translate.BRIDGE
    assert translate.route("px4", "gcs", "lost").how == translate.CLIENT


def _truth(t, alt, ne=None, vel=None, tilt=None) -> Truth:
    t = np.asarray(t, float)
    alt = np.asarray(alt, float)
    ne = np.zeros((len(t), 2)) if ne is None else np.asarray(ne, float)
    vel = np.c_[np.zeros((len(t), 2)), -np.gradient(alt, t)] if vel is None else vel
    return Truth(t, ne, alt, vel, np.zeros(len(t)) if tilt is None else np.asarray(tilt))


def test_detection_is_the_first_alert_or_failsafe_mode_change():
    t = np.linspace(0, 100, 1001)
    tr = _truth(t, np.where(t < 60, ALT_M, np.maximum(ALT_M - 0.5 * (t - 60), 0.0)))
    tl = Timeline(modes=[(10.0, GUIDED, True), (58.0, LAND, True)],
                  texts=[(52.0, 6, "EKF3 IMU0 is using GPS"), (57.0, 2, "EKF variance")])
    action = first_action("ardupilot", tl, 50.0, 80.0, tr, "hold")
    assert action == (58.0, "LAND")
    assert detection("ardupilot", tl, 50.0, 80.0, action) == (7.0, "EKF variance")
    quiet = Timeline(modes=[(10.0, GUIDED, True)], texts=[(52.0, 6, "info only")])
    d, by = detection("ardupilot", quiet, 50.0, 80.0, None)
    assert math.isnan(d) and by == ""
    # our FC announcing the injection itself (a scenario's rc entry) is not a detection
    echo = Timeline(modes=[(10.0, AUTO, True)], texts=[(50.0, 4, "Failure injected: rc lost"),
                                                      (51.0, 4, "Radio Failsafe")])
    assert detection("ours", echo, 50.0, 80.0, None) == (1.0, "Radio Failsafe")


def test_a_hold_where_the_mission_ends_is_not_an_action():
    hold = (3 << 24) | (4 << 16)            # PX4 AUTO.LOITER
    mission = (4 << 24) | (4 << 16)
    t = np.linspace(0, 200, 2001)
    tr = _truth(t, np.full_like(t, ALT_M), ne=np.zeros((len(t), 2)))   # at (0, 0): the end
    tl = Timeline(modes=[(70.0, mission, True), (150.0, hold, True)])
    assert first_action("px4", tl, 80.0, 200.0, tr, "mission") is None
    away = _truth(t, np.full_like(t, ALT_M), ne=np.full((len(t), 2), 40.0))
    assert first_action("px4", tl, 80.0, 200.0, away, "mission") == (150.0, "HOLD")
    # PX4 holds COM_FAIL_ACT_T before its failsafe acts: the action is named with both.
    rtl = (5 << 24) | (4 << 16)
    failsafe = Timeline(modes=[(70.0, mission, True), (85.0, hold, True), (90.0, rtl, True)])
    assert first_action("px4", failsafe, 80.0, 200.0, away, "mission") == (85.0, "HOLD>RTL")


def test_outcome_tells_a_fall_from_a_landing():
    t = np.linspace(0, 40, 4001)
    landing = np.maximum(ALT_M - 0.5 * t, 0.0)      # 0.5 m/s down to the ground
    assert outcome(_truth(t, landing), 0.0) == "landed upright"
    fall = np.maximum(ALT_M - 0.5 * 9.81 * t ** 2, 0.0)    # free fall: ~14 m/s at impact
    assert outcome(_truth(t, fall), 0.0) == "crashed"
    assert outcome(_truth(t, np.full_like(t, ALT_M)), 0.0) == "still flying"
    tipped = _truth(t, landing, tilt=np.where(t > 30, 90.0, 0.0))
    assert outcome(tipped, 0.0) == "crashed"


def test_a_crash_checks_disarm_is_on_the_ground():
    t = np.linspace(0, 40, 4001)
    fall = np.maximum(ALT_M - 0.5 * 9.81 * (t - 10).clip(0) ** 2, 0.0)   # ground at ~11.4 s
    tr = _truth(t, fall, tilt=np.where(t > 12, 90.0, 0.0))
    crash_check = Timeline(modes=[(5.0, GUIDED, True), (14.0, GUIDED, False)])
    assert disarm(crash_check, 10.0, tr) == "on the ground"
    assert disarm_time(crash_check, 10.0) == 14.0
    assert disarm(Timeline(modes=[(5.0, GUIDED, True), (10.5, GUIDED, False)]), 10.0, tr) \
        == "in the air"
    assert disarm(Timeline(modes=[(5.0, GUIDED, True)]), 10.0, tr) == "none"
    # the in-air disarm is an action; the one on the ground after the crash is not
    assert first_action("ardupilot", crash_check, 10.0, 40.0, tr, "hold") is None


# ---- real flights --------------------------------------------------------------------------
def _fly(fc: str, name: str, tmp_path, **kw):
    r = run_one(fc, name, 1, str(tmp_path), speed=10.0, **kw)
    assert r.status == "ok", r.reason
    return r


def test_ours_gnss_off_in_hold_lands(tmp_path):
    r = _fly("ours", "F2", tmp_path)
    m = r.metrics
    assert m["action"] == "LAND" and m["outcome"] == "landed upright", m
    assert 0.0 <= m["detect_s"] <= 30.0


def test_ours_battery_capacity_loss_in_auto_returns(tmp_path):
    r = _fly("ours", "F8", tmp_path)
    m = r.metrics
    assert m["action"] == "RTL" and m["land_expected"] == "home", m
    assert m["volts_min_after"] < translate_low_volt()


def translate_low_volt() -> float:
    from silbridge.tools.benchmark.failures.failsafe_params import LOW_VOLT
    return LOW_VOLT


needs_arducopter = pytest.mark.skipif(
    not ARDUCOPTER, reason="SILBRIDGE_ARDUCOPTER is not set: no ArduCopter 4.6 SITL binary to "
                           "fly (tools/autopilots/ardupilot/sitl.py says how to build one)")


@needs_arducopter
def test_arducopter_gnss_off_in_hold_gives_ekf_failsafe_land(tmp_path):
    r = _fly("ardupilot", "F2", tmp_path, binary=ARDUCOPTER)
    assert r.sim_params[0][1] == {"SIM_GPS_DISABLE": 1}
    m = r.metrics
    assert m["action"] == "LAND" and m["outcome"] == "landed upright", m
    assert any("EKF" in text for _, _, text in r.texts)


@needs_arducopter
def test_arducopter_battery_capacity_loss_in_auto_gives_rtl(tmp_path):
    r = _fly("ardupilot", "F8", tmp_path, binary=ARDUCOPTER)
    (t, values), = r.sim_params
    assert t == pytest.approx(80.0, abs=0.01) and values["SIM_BATT_VOLTAGE"] < translate_low_volt()
    m = r.metrics
    assert m["action"] == "RTL" and m["land_expected"] == "home", m
