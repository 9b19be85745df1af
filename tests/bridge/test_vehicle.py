"""The quad model: figures in range, hover, motor order and spin, ground contact, crashes."""

import math

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator

AIR = {"home.initial_agl_m": 20.0}


def airborne_hover(extra=None, settle_steps=800):
    sim = Simulator(load_scenario("S1", overrides={**AIR, **(extra or {})}))
    pwm = [sim.hover_pwm_us] * 4
    for _ in range(settle_steps):      # rotors spin up from rest (tau 25 ms)
        sim.step(pwm)
    return sim, pwm


def test_thrust_to_weight_and_hover_throttle_in_range():
    sim = Simulator(load_scenario("S1"))
    assert 2.0 <= sim.thrust_to_weight <= 4.0
    assert 0.40 <= sim.hover_throttle <= 0.55
    assert 1400 <= sim.hover_pwm_us <= 1550
    assert sim.fdm.mass_kg == pytest.approx(1.5, rel=1e-6)


def test_open_loop_hover_pwm_gives_zero_vertical_acceleration():
    sim, pwm = airborne_hover(settle_steps=3000)
    v0 = sim.truth()["vel_ned_m_s"][2]
    for _ in range(1000):
        sim.step(pwm)
    t = sim.truth()
    accel_down = (t["vel_ned_m_s"][2] - v0) / 1.0
    assert abs(accel_down) < 0.05                       # m/s^2 over one second
    # Thrust balances weight (drag of the slow residual sink aside).
    g = sim.fdm.fdm["accelerations/gravity-ft_sec2"] * 0.3048
    assert t["specific_force_frd_m_s2"][2] == pytest.approx(-g, abs=0.05)
    assert max(abs(a) for a in t["euler_rad"][:2]) < 1e-6   # symmetric: stays level


@pytest.mark.parametrize("motor, roll_sign, pitch_sign, yaw_sign", [
    # A weak motor drops its corner; the lost reaction torque yaws the other way.
    (1, +1, -1, -1),   # front-right, CCW: roll right, nose down, yaw left
    (2, -1, +1, -1),   # back-left, CCW: roll left, nose up, yaw left
    (3, -1, -1, +1),   # front-left, CW: roll left, nose down, yaw right
    (4, +1, +1, +1),   # back-right, CW: roll right, nose up, yaw right
])
def test_motor_bias_moment_signs(motor, roll_sign, pitch_sign, yaw_sign):
    sim, pwm = airborne_hover()
    sim.fdm.set_thrust_scale(motor - 1, 0.9)
    for _ in range(50):
        sim.step(pwm)
    p, q, r = sim.truth()["rates_frd_rad_s"]
    assert np.sign(p) == roll_sign and abs(p) > 0.05
    assert np.sign(q) == pitch_sign and abs(q) > 0.05
    assert np.sign(r) == yaw_sign and abs(r) > 0.002


def test_pwm_channel_order_matches_motor_positions():
    # More PWM on channel 0 (motor 1, front-right) must roll left and pitch up.
    sim, pwm = airborne_hover()
    for _ in range(50):
        sim.step([pwm[0] + 50, pwm[1], pwm[2], pwm[3]])
    p, q, r = sim.truth()["rates_frd_rad_s"]
    assert p < 0 and q > 0 and r > 0


def test_rests_on_its_legs_without_bounce():
    sim = Simulator(load_scenario("S1"))
    z = []
    for _ in range(2000):
        sim.step([1000] * 4)
        z.append(sim.truth()["pos_ned_m"][2])
    assert sim.truth()["on_ground"]
    assert max(abs(v) for v in z) < 1e-4
    assert not sim.crashed


def _fly_vertical(sim, target_vd_fn, steps):
    """A vertical-speed P loop on truth, as a stand-in FC for take-off/landing tests."""
    for _ in range(steps):
        t = sim.truth()
        vd_err = target_vd_fn(t) - t["vel_ned_m_s"][2]
        pwm = min(2000.0, max(1000.0, sim.hover_pwm_us - 150.0 * vd_err))
        sim.step([pwm] * 4)


def test_take_off_and_soft_landing_are_real():
    sim = Simulator(load_scenario("S1"))
    _fly_vertical(sim, lambda t: -1.0, 3000)          # climb at 1 m/s for 3 s
    t = sim.truth()
    assert not t["on_ground"] and -3.2 < t["pos_ned_m"][2] < -2.0
    _fly_vertical(sim, lambda t: 0.5, 7000)           # descend at 0.5 m/s
    t = sim.truth()
    assert t["on_ground"] and abs(t["pos_ned_m"][2]) < 0.01
    assert not sim.crashed


def test_hard_touchdown_is_a_crash():
    sim = Simulator(load_scenario("S1", overrides={"home.initial_agl_m": 2.0}))
    for _ in range(1500):                             # motors off: free fall from 2 m
        sim.step([1000] * 4)
    assert sim.crashed and "touchdown" in sim.crash_reason
    assert any("crash" in text for _, text in sim.events)


def test_full_roll_flip_is_a_crash():
    sim, pwm = airborne_hover()
    for _ in range(3000):
        sim.step([1900, 1000, 1000, 1900])            # right side full, left side off
    assert sim.crashed


def test_external_force_accelerates_the_vehicle():
    sc = load_scenario("S1", overrides={**AIR, "disturbance": [
        {"type": "force", "frame": "ned", "axis": "y", "amplitude_g": 0.5, "start_s": 1.0}]})
    sim = Simulator(sc)
    pwm = [sim.hover_pwm_us] * 4
    for _ in range(1000):
        sim.step(pwm)
    assert not sim.events               # step 1001 is the first to start at 1.0 s
    sim.step(pwm)
    assert sim.events and "force on" in sim.events[0][1]
    assert sim.events[0][0] == 1_000_000_000
    # At rest the accelerometer feels the whole push (0.5 g east, level: body y).
    assert sim.truth()["specific_force_frd_m_s2"][1] == pytest.approx(0.5 * 9.80665, abs=0.01)
    ve0 = sim.truth()["vel_ned_m_s"][1]
    for _ in range(500):
        sim.step(pwm)
    ve = sim.truth()["vel_ned_m_s"][1]
    # 0.5 g east for 0.5 s: 2.45 m/s, minus a little drag.
    assert 2.2 < ve - ve0 < 2.46


def test_wind_pushes_the_vehicle_downwind():
    sc = load_scenario("S1", overrides={**AIR, "disturbance": [
        {"type": "wind", "speed_m_s": 8.0, "from_deg": 270.0, "start_s": 0.5}]})
    sim = Simulator(sc)
    pwm = [sim.hover_pwm_us] * 4
    for _ in range(4000):
        sim.step(pwm)
    vn, ve, _ = sim.truth()["vel_ned_m_s"]
    assert ve > 0.5 and abs(vn) < 0.05                  # wind from the west blows east
    assert math.isfinite(ve)


def test_air_start_is_above_home_and_nan_pwm_is_refused():
    sim = Simulator(load_scenario("S1", overrides={"home.initial_agl_m": 7.0}))
    sim.step([1000] * 4)
    assert sim.truth()["pos_ned_m"][2] == pytest.approx(-7.0, abs=1e-3)
    with pytest.raises(ValueError, match="NaN"):
        sim.step([1500, float("nan"), 1500, 1500])
