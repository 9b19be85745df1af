"""Baro, magnetometer and GNSS: ISA pressure, rotated field, latency and rates."""

import math

import numpy as np
import pytest

from silbridge.bridge.atmosphere import isa_pressure_pa
from silbridge.bridge.frames import ned_to_frd
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from bridge_test_helpers import QUIET_LOWRATE, collect, of_kind


@pytest.mark.parametrize("ground_alt_m", [0.0, 488.0, 2000.0])
def test_baro_matches_isa_at_altitude(ground_alt_m):
    sc = load_scenario("S1", overrides={**QUIET_LOWRATE, "home.alt_m": ground_alt_m})
    sim = Simulator(sc)
    baro = of_kind(collect(sim, [1000] * 4, 1000), Kind.BARO)
    assert len(baro) == 100                                     # 100 Hz
    alt = sim.truth()["alt_msl_m"]
    assert baro["pressure_pa"][-1] == pytest.approx(isa_pressure_pa(alt), abs=2.0)
    t_isa_c = 15.0 - 0.0065 * alt * 6356766 / (6356766 + alt)
    assert baro["temperature_c"][-1] == pytest.approx(t_isa_c, abs=0.05)


def test_baro_noise_and_lag():
    sc = load_scenario("S1", overrides={"baro.lag_s": 0.0})
    sim = Simulator(sc)
    p = of_kind(collect(sim, [1000] * 4, 5000), Kind.BARO)["pressure_pa"].astype(float)
    assert p.std() == pytest.approx(1.2, rel=0.25)              # MS5611 OSR 4096 RMS
    # With lag, a climb reads late: the lagged pressure is above the true one.
    sc = load_scenario("S1", overrides={"baro.noise_pa": 0.0, "baro.lag_s": 0.05})
    sim = Simulator(sc)
    recs = collect(sim, [1800] * 4, 1500)
    true_p = sim.truth()["pressure_pa"]
    assert of_kind(recs, Kind.BARO)["pressure_pa"][-1] > true_p + 1.0


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, 225.0])
def test_mag_is_the_configured_field_rotated_into_the_body(heading_deg):
    field = [0.21, 0.02, 0.43]
    sc = load_scenario("S1", overrides={**QUIET_LOWRATE, "mag.field_ned_gauss": field,
                                        "home.heading_deg": heading_deg,
                                        "home.initial_agl_m": 10.0})
    sim = Simulator(sc)
    pwm = [sim.hover_pwm_us + 30, sim.hover_pwm_us, sim.hover_pwm_us, sim.hover_pwm_us - 30]
    recs = collect(sim, pwm, 300)                               # some roll and pitch
    mag = of_kind(recs, Kind.MAG)
    assert len(mag) == 30
    phi, theta, psi = sim.truth()["euler_rad"]
    assert abs(phi) > 0.003
    assert np.allclose(mag["field_frd_gauss"][-1], ned_to_frd(phi, theta, psi, field), atol=1e-6)
    if heading_deg == 90.0:   # facing east: body x sees east, body y sees south
        first = mag["field_frd_gauss"][0]
        assert np.allclose(first, [0.02, -0.21, 0.43], atol=2e-3)


def test_mag_noise():
    sim = Simulator(load_scenario("S1"))
    m = of_kind(collect(sim, [1000] * 4, 5000), Kind.MAG)["field_frd_gauss"].astype(float)
    assert np.allclose(m.std(axis=0), 0.0032, rtol=0.25)


def test_gnss_latency_rate_and_fields():
    sc = load_scenario("S1", overrides={**QUIET_LOWRATE, "home.initial_agl_m": 20.0})
    sim = Simulator(sc)
    dt = sim.dt_ns
    truth_at = {}
    fixes = []
    for k in range(1, 1001):
        recs = sim.step([1300] * 4)                              # sinking: position changes
        t = sim.truth()
        truth_at[k * dt] = t
        fixes += list(of_kind(recs, Kind.GNSS))
    # Epochs every 100 ms, each published 110 ms later: 8 fixes in 1 s (210..910 ms).
    assert [int(f["sim_ns"]) for f in fixes] == [(m * 100 + 110) * 1_000_000 for m in range(1, 9)]
    for f in fixes:
        epoch = int(f["sim_ns"]) - 110_000_000
        t = truth_at[epoch]
        assert f["alt_mm"] == round(t["alt_msl_m"] * 1000)
        assert np.allclose(f["vel_ned_m_s"], t["vel_ned_m_s"], atol=5.01e-3)   # whole cm/s (HIL_GPS)
        lat = math.radians(47.397742) + t["pos_ned_m"][0] / sim.fdm.m_per_rad_lat
        assert abs(f["lat_e7"] - math.degrees(lat) * 1e7) <= 1
        assert f["fix_type"] == 3 and f["satellites"] == 14
    assert fixes[-1]["vel_ned_m_s"][2] > 0.5                      # descending


def test_gnss_error_is_correlated_with_the_configured_sigma():
    sc = load_scenario("S1", overrides={"gnss.pos_tau_s": 1.0})
    sim = Simulator(sc)
    fixes = of_kind(collect(sim, [1000] * 4, 60000), Kind.GNSS)
    north_m = (fixes["lat_e7"] / 1e7 - 47.397742) * math.radians(1) * sim.fdm.m_per_rad_lat
    assert north_m.std() == pytest.approx(2.12, rel=0.3)
    # Gauss-Markov at 10 Hz with tau 1 s: lag-1 autocorrelation exp(-0.1) = 0.905.
    r1 = np.corrcoef(north_m[:-1], north_m[1:])[0, 1]
    assert r1 == pytest.approx(math.exp(-0.1), abs=0.05)
