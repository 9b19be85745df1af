"""IMU model: rest readings, noise density, oversampled sample times, interpolation."""

import math

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from bridge_test_helpers import QUIET_IMU, collect, of_kind

G = 9.80665


def rest_imu(overrides=None, imu_hz=None, steps=2000):
    sim = Simulator(load_scenario("S1", overrides=overrides), imu_hz=imu_hz)
    recs = collect(sim, [1000] * 4, steps)
    return sim, of_kind(recs, Kind.IMU)


def test_at_rest_accel_reads_minus_g_and_gyro_reads_its_bias():
    sim, imu = rest_imu()
    acc = imu["accel_frd_m_s2"].astype(float)
    gyr = imu["gyro_frd_rad_s"].astype(float)
    bias = sim.truth()
    gb = np.array(bias["imu_bias_gyro_frd_rad_s"])
    ab = np.array(bias["imu_bias_accel_frd_m_s2"])
    # Means over 2 s: noise averages to ~3e-4; the bias walk moves ~1e-4.
    assert acc[:, 2].mean() - ab[2] == pytest.approx(-G, abs=0.03)
    # x, y: the accel bias walk (6e-3 m/s^3/sqrt(Hz)) moves ~0.01 in 2 s.
    assert np.allclose(acc[:, :2].mean(axis=0) - ab[:2], 0.0, atol=0.03)
    assert np.allclose(gyr.mean(axis=0), gb, atol=1e-4)
    # Turn-on biases are drawn with the configured sigmas (8.7e-3 rad/s, 0.0196 m/s^2).
    assert 0 < np.abs(gb).max() < 5 * 8.7e-3 and 0 < np.abs(ab).max() < 5 * 0.0196


def test_quiet_imu_at_rest_reads_exactly_the_truth():
    sim, imu = rest_imu(QUIET_IMU, steps=500)
    acc = imu["accel_frd_m_s2"].astype(float)
    assert np.allclose(acc[-1], sim.truth()["specific_force_frd_m_s2"], atol=1e-5)
    assert np.abs(imu["gyro_frd_rad_s"]).max() < 1e-6


@pytest.mark.parametrize("imu_hz", [1000, 8000])
def test_white_noise_matches_its_density(imu_hz):
    nd_g, nd_a = 4.887e-5, 6.865e-4
    over = {k: v for k, v in QUIET_IMU.items() if "noise_density" not in k}
    sim, imu = rest_imu(over, imu_hz=imu_hz, steps=4000)
    # One-sided density over the Nyquist band: sigma = ND * sqrt(rate / 2).
    sg = imu["gyro_frd_rad_s"].astype(float).std(axis=0)
    sa = imu["accel_frd_m_s2"].astype(float).std(axis=0)
    n = len(imu)
    tol = 4.0 / math.sqrt(2 * n)          # 4 sigma of a std estimate
    assert np.allclose(sg, nd_g * math.sqrt(imu_hz / 2), rtol=tol)
    assert np.allclose(sa, nd_a * math.sqrt(imu_hz / 2), rtol=tol)


@pytest.mark.parametrize("imu_hz, n", [(1000, 1), (2000, 2), (8000, 8), (32000, 32)])
def test_oversampled_counts_and_times(imu_hz, n):
    sim = Simulator(load_scenario("S1"), imu_hz=imu_hz)
    dt = sim.dt_ns
    seq = 0
    for k in range(1, 6):
        recs = sim.step([1000] * 4)
        imu = of_kind(recs, Kind.IMU)
        assert len(imu) == n
        assert (recs["kind"][:n] == int(Kind.IMU)).all()          # IMU first, oldest first
        expect = [(k - 1) * dt + (j + 1) * dt // n for j in range(n)]
        assert imu["sim_ns"].tolist() == expect
        assert imu["sim_ns"][-1] == k * dt == sim.sim_ns           # last sample is the step
        assert imu["sample_index"].tolist() == list(range(n))
        assert (imu["samples_per_step"] == n).all()
        assert imu["seq"].tolist() == list(range(seq, seq + n))
        seq += n


def test_non_multiple_rate_follows_the_sample_time_rule():
    # 1500 Hz at 1 kHz physics: sample m at floor(m * 1e9 / 1500) ns, each in the
    # step that ends at or after it: counts alternate 1, 2, totalling 1500 per second.
    sim = Simulator(load_scenario("S1"), imu_hz=1500)
    recs = collect(sim, [1000] * 4, 1000)
    imu = of_kind(recs, Kind.IMU)
    assert len(imu) == 1500
    m = np.arange(1, 1501)
    assert (imu["sim_ns"] == (m * 10**9) // 1500).all()
    # 500 Hz: every other step has no IMU record.
    sim = Simulator(load_scenario("S1"), imu_hz=500)
    counts = [len(of_kind(sim.step([1000] * 4), Kind.IMU)) for _ in range(10)]
    assert counts == [0, 1] * 5


def test_oversampling_interpolates_between_physics_states():
    sim = Simulator(load_scenario("S1", overrides={**QUIET_IMU, "home.initial_agl_m": 5.0}),
                    imu_hz=8000)
    prev = None
    for _ in range(300):              # motors spin up: specific force changes every step
        recs = sim.step([1700] * 4)
        imu = of_kind(recs, Kind.IMU)
        az = imu["accel_frd_m_s2"][:, 2].astype(float)
        now = sim.truth()["specific_force_frd_m_s2"][2]
        if prev is not None:
            expect = prev + (now - prev) * (np.arange(1, 9) / 8.0)
            assert np.allclose(az, expect, atol=1e-4)
        prev = now


def test_vibration_follows_rotor_speed():
    over = {k: v for k, v in QUIET_IMU.items() if not k.startswith("imu.vib")}
    sim = Simulator(load_scenario("S1", overrides={**over, "home.initial_agl_m": 20.0}),
                    imu_hz=8000)
    phases = np.array(sim.imu.phase)           # seeded rotor phases at start
    idle = of_kind(collect(sim, [1000] * 4, 200), Kind.IMU)
    assert np.abs(idle["accel_frd_m_s2"][:, :2]).max() < 1e-5        # rotors stopped
    hover = of_kind(collect(sim, [sim.hover_pwm_us] * 4, 500), Kind.IMU)
    acc = hover["accel_frd_m_s2"][-2000:].astype(float)
    acc -= acc.mean(axis=0)
    # Equal rotor speeds keep the phase offsets: the 1/rev sum on x is
    # A s^2 |sum exp(i p)| cos(...), on y A s^2 |sum spin exp(i p)| sin(...).
    omega = sim.truth()["rotor_rad_s"][0]
    amp = 2.0 * (omega / sim.omega_max_rad_s) ** 2
    spin = np.array([-1.0, -1.0, 1.0, 1.0])
    rms_x = amp * abs(np.exp(1j * phases).sum()) / math.sqrt(2)
    rms_y = amp * abs((spin * np.exp(1j * phases)).sum()) / math.sqrt(2)
    assert acc[:, 0].std() == pytest.approx(rms_x, rel=0.05)
    assert acc[:, 1].std() == pytest.approx(rms_y, rel=0.05)
    # The spectrum peaks at the rotor rotation frequency (~81 Hz at hover).
    spec = np.abs(np.fft.rfft(acc[:, 1]))
    freqs = np.fft.rfftfreq(len(acc), 1 / 8000)
    assert abs(freqs[spec.argmax()] - omega / (2 * math.pi)) < 4.0


def test_injected_constant_gyro_bias():
    sim, imu = rest_imu({**QUIET_IMU, "imu.gyro_bias_rad_s": [0.01, -0.02, 0.03]}, steps=50)
    assert np.allclose(imu["gyro_frd_rad_s"][-1], [0.01, -0.02, 0.03], atol=1e-6)


def test_temperature_warms_up_from_ambient():
    sim, imu = rest_imu(steps=3000)
    temp = imu["temperature_c"].astype(float)
    ambient = 15.0 - 0.0065 * 488.1          # ISA at the home elevation
    assert temp[0] == pytest.approx(ambient, abs=0.05)
    assert (np.diff(temp) >= 0).all() and temp[-1] > temp[0]
    # 10 K rise, tau 120 s: after 3 s, 10 * (1 - exp(-3/120)) = 0.247 K.
    assert temp[-1] - ambient == pytest.approx(10 * (1 - math.exp(-3 / 120)), abs=0.01)
