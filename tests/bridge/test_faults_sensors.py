"""Sensor faults of issue 28 in the records they target (bridge/faults/sensors.py, gnss.py,
bridge/src/sensor_faults.c): one open-loop flight carries a fault of each kind in its own
window, against the same flight without failures. Sensor faults change no physics and no
noise stream, so every record outside a fault's window, and the ground truth throughout, is
the fault-free run's byte for byte; inside, the record shows exactly the fault.

Real JSBSim, the real C step kernel; windows: a fault switched on at at_s acts on the
samples of sim time (at_s, at_s + duration_s].
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bridge_test_helpers import collect, of_kind
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

_NS = 1_000_000_000
_GNSS_LATENCY_NS = 110_000_000     # the scenario default (gnss.latency_s)
_R_AIR, _G0 = 287.05287, 9.80665
_P_QUANTUM_PA = 0.8     # the pressure grid HIL_SENSOR carries (mavlink/hil/hil_quant.py)


def _f(unit, type, at_s, duration_s, **params):
    return {"unit": unit, "type": type, "at_s": at_s, "duration_s": duration_s, **params}


FAILURES = [
    _f("gyro", "stuck", 0.5, 0.5),
    _f("accel", "bias", 1.0, 0.5, bias=[0.0, 0.0, 0.5]),
    _f("gyro", "clip", 1.5, 0.5, limit=0.002),
    _f("accel", "noisy", 2.0, 0.5, axis=3, sigma=1.0),
    _f("baro", "glitch", 0.5, 0.5, offset_m=10.0),
    _f("baro", "drift", 1.2, 0.8, rate_m_s=0.2),
    _f("baro", "stuck", 2.2, 0.4),
    _f("mag", "off", 0.5, 0.5),
    _f("mag", "motor_interference", 1.5, 1.0, gauss_per_a=[0.005, 0.005, 0.01]),
    _f("gnss", "glitch", 0.5, 0.5, offset_m=[20.0, -10.0, 0.0]),
    _f("gnss", "fix_lost", 1.2, 0.3),
    _f("gnss", "vel_error", 1.6, 0.3, error_m_s=[1.0, 0.0, -0.5]),
    _f("gnss", "off", 2.0, 0.3),
    _f("gnss", "sats_drop", 2.4, 0.6, satellites=2, ramp_s=0.4),
]
STEPS = 3000


def _flight(failures):
    sim = Simulator(load_scenario("S1", overrides={"duration_s": 3.0, "failure": failures}))
    recs = collect(sim, (sim.hover_pwm_us + 30.0,) * 4, STEPS)
    return sim, recs


@pytest.fixture(scope="module")
def flights():
    return _flight(FAILURES), _flight([])


def _window(recs, at_s, duration_s, shift_ns=0):
    t = recs["sim_ns"] - shift_ns
    return (t > int(at_s * _NS)) & (t <= int(round((at_s + duration_s) * _NS)))


def _in_any_window(recs, unit, shift_ns=0):
    mask = np.zeros(len(recs), bool)
    for f in FAILURES:
        if f["unit"] == unit:
            mask |= _window(recs, f["at_s"], f["duration_s"], shift_ns)
    return mask


def test_switches_are_events_and_truth_is_untouched(flights):
    (sim, recs), (_, ref) = flights
    events = [text for _, text in sim.drain_events() if text.startswith("failure")]
    ends_in_run = sum(f["at_s"] + f["duration_s"] < 3.0 for f in FAILURES)
    assert len(events) == len(FAILURES) + ends_in_run    # the last one runs to the end
    assert "failure[0] on: gyro.stuck[1] axis=0" in events
    for kind in (Kind.GT_ATT, Kind.GT_NAV):
        assert of_kind(recs, kind).tobytes() == of_kind(ref, kind).tobytes()


@pytest.mark.parametrize("unit, kind", [("gyro", Kind.IMU), ("baro", Kind.BARO),
                                        ("gnss", Kind.GNSS)])
def test_records_outside_the_windows_are_the_fault_free_runs(flights, unit, kind):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, kind), of_kind(ref, kind)
    if kind == Kind.IMU:   # gyro and accel windows together
        keep = ~(_in_any_window(a, "gyro") | _in_any_window(a, "accel"))
        assert a[keep].tobytes() == b[keep].tobytes()
    elif kind == Kind.BARO:
        keep = ~_in_any_window(a, "baro")
        assert a[keep].tobytes() == b[keep].tobytes()
    else:   # before the first GNSS fault's fixes arrive
        first = min(f["at_s"] for f in FAILURES if f["unit"] == "gnss")
        early_a = a[a["sim_ns"] <= first * _NS + _GNSS_LATENCY_NS]
        early_b = b[b["sim_ns"] <= first * _NS + _GNSS_LATENCY_NS]
        assert len(early_a) > 3 and early_a.tobytes() == early_b.tobytes()


def test_gyro_stuck_repeats_one_sample(flights):
    (_, recs), (_, ref) = flights
    g = of_kind(recs, Kind.IMU)
    w = _window(g, 0.5, 0.5)
    stuck = g["gyro_frd_rad_s"][w]
    assert len(stuck) == 500 and (stuck == stuck[0]).all()
    assert len(np.unique(of_kind(ref, Kind.IMU)["gyro_frd_rad_s"][w][:, 0])) > 400


def test_accel_bias_step_adds_exactly_the_bias(flights):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.IMU), of_kind(ref, Kind.IMU)
    w = _window(a, 1.0, 0.5)
    d = a["accel_frd_m_s2"][w].astype(float) - b["accel_frd_m_s2"][w]
    np.testing.assert_allclose(d, np.tile([0.0, 0.0, 0.5], (500, 1)), atol=1e-5)


def test_gyro_clip_saturates_at_the_limit(flights):
    (_, recs), _ = flights
    g = of_kind(recs, Kind.IMU)["gyro_frd_rad_s"][_window(of_kind(recs, Kind.IMU), 1.5, 0.5)]
    assert np.abs(g).max() == np.float32(0.002)
    assert (np.abs(g) == np.float32(0.002)).mean() > 0.5   # the turn-on bias alone exceeds it


def test_accel_noisy_axis_gets_its_sigma_and_only_it(flights):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.IMU), of_kind(ref, Kind.IMU)
    w = _window(a, 2.0, 0.5)
    d = a["accel_frd_m_s2"][w].astype(float) - b["accel_frd_m_s2"][w]
    assert (d[:, :2] == 0).all()
    assert 0.85 < d[:, 2].std() < 1.15 and abs(d[:, 2].mean()) < 0.15


def _rho(baro):
    return baro["pressure_pa"].astype(float) / (_R_AIR * (baro["temperature_c"] + 273.15))


def test_baro_glitch_and_drift_are_altitude_errors_in_pressure(flights):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.BARO), of_kind(ref, Kind.BARO)
    dp = a["pressure_pa"].astype(float) - b["pressure_pa"]
    w = _window(a, 0.5, 0.5)
    np.testing.assert_allclose(dp[w], -_rho(b[w]) * _G0 * 10.0, atol=_P_QUANTUM_PA)
    w = _window(a, 1.2, 0.8)
    t_s = (a["sim_ns"][w] - 1.2 * _NS) / _NS
    np.testing.assert_allclose(dp[w], -_rho(b[w]) * _G0 * 0.2 * t_s, atol=_P_QUANTUM_PA)
    assert dp[w][-1] < -1.0    # 16 cm of drift at the end of the window: -1.8 Pa


def test_baro_stuck_holds_a_reading(flights):
    (_, recs), _ = flights
    a = of_kind(recs, Kind.BARO)
    p = a["pressure_pa"][_window(a, 2.2, 0.4)]
    assert len(p) == 40 and (p == p[0]).all()


def test_mag_off_sends_no_records_then_resumes(flights):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.MAG), of_kind(ref, Kind.MAG)
    assert not _window(a, 0.5, 0.5).any()
    assert _window(b, 0.5, 0.5).sum() == 50
    assert (np.diff(a["seq"].astype(np.int64)) == 1).all()   # silent, not dropped
    after = (a["sim_ns"] > 1.0 * _NS) & (a["sim_ns"] <= 1.5 * _NS)
    after_b = (b["sim_ns"] > 1.0 * _NS) & (b["sim_ns"] <= 1.5 * _NS)
    assert (a["field_frd_gauss"][after] == b["field_frd_gauss"][after_b]).all()


def test_mag_motor_interference_follows_the_battery_current(flights):
    (sim, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.MAG), of_kind(ref, Kind.MAG)
    sa = a[_window(a, 1.5, 1.0)]
    sb = b[_window(b, 1.5, 1.0)]
    d = sa["field_frd_gauss"].astype(float) - sb["field_frd_gauss"]
    current_a = d[:, 2] / 0.01
    assert current_a.min() > 5.0     # the motors draw several amperes near hover
    np.testing.assert_allclose(d[:, 0], 0.005 * current_a, rtol=1e-3, atol=2e-7)
    np.testing.assert_allclose(d[:, 1], 0.005 * current_a, rtol=1e-3, atol=2e-7)


def _epochs(g):
    return (g["sim_ns"] - _GNSS_LATENCY_NS) / _NS


def test_gnss_glitch_moves_the_position_by_the_offset(flights):
    (sim, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.GNSS), of_kind(ref, Kind.GNSS)
    w = _window(a, 0.5, 0.5, _GNSS_LATENCY_NS)
    assert w.sum() == 5
    a, b = a[w], b[np.isin(b["sim_ns"], a["sim_ns"][w])]
    dn = (a["lat_e7"] - b["lat_e7"]) * 1e-7 * math.radians(1) * sim.fdm.m_per_rad_lat
    de = (a["lon_e7"] - b["lon_e7"]) * 1e-7 * math.radians(1) * sim.fdm.m_per_rad_lon
    np.testing.assert_allclose(dn, 20.0, atol=0.02)
    np.testing.assert_allclose(de, -10.0, atol=0.02)


def _by_epoch(g, at_s, duration_s):
    return g[_window(g, at_s, duration_s, _GNSS_LATENCY_NS)]


def test_gnss_fix_lost_and_off_and_vel_error(flights):
    (_, recs), (_, ref) = flights
    a, b = of_kind(recs, Kind.GNSS), of_kind(ref, Kind.GNSS)
    lost = _by_epoch(a, 1.2, 0.3)
    assert len(lost) == 3 and (lost["fix_type"] == 1).all() and (lost["satellites"] == 0).all()
    assert (lost["eph_cm"] == 65535).all() and (lost["lat_e7"] == 0).all()
    assert len(_by_epoch(a, 2.0, 0.3)) == 0 and len(_by_epoch(b, 2.0, 0.3)) == 3
    va, vb = _by_epoch(a, 1.6, 0.3), _by_epoch(b, 1.6, 0.3)
    np.testing.assert_allclose(va["vel_ned_m_s"].astype(float) - vb["vel_ned_m_s"],
                               np.tile([1.0, 0.0, -0.5], (3, 1)), atol=1e-5)


def test_gnss_sats_drop_degrades_then_loses_the_fix(flights):
    (_, recs), _ = flights
    g = _by_epoch(of_kind(recs, Kind.GNSS), 2.4, 0.6)
    sats = g["satellites"].tolist()
    assert sats == sorted(sats, reverse=True) and sats[0] < 14 and sats[-1] == 2
    with_fix = g[g["satellites"] >= 4]
    assert (np.diff(with_fix["eph_cm"].astype(int)) >= 0).all() and with_fix["eph_cm"][-1] > 212
    assert (with_fix["fix_type"] == 3).all()
    assert (g[g["satellites"] < 3]["fix_type"] == 1).all()
