"""Disturbance switching and scripted setpoints (S2, S3, S4, S5 in short form)."""

import math

import numpy as np
import pytest

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.setpoints import SetpointProgram
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

from bridge_test_helpers import QUIET_IMU, collect, of_kind


def test_gyro_bias_step_and_ramp_appear_in_the_gyro():
    over = {**QUIET_IMU, "disturbance": [
        {"type": "gyro_bias", "axis": "x", "amplitude_rad_s": 0.04, "start_s": 0.1},
        {"type": "gyro_bias", "axis": "z", "amplitude_rad_s": 0.03, "sign": -1.0,
         "ramp_s": 0.2, "start_s": 0.1, "stop_s": 0.5}]}
    sim = Simulator(load_scenario("S1", overrides=over))
    gyro = of_kind(collect(sim, [1000] * 4, 600), Kind.IMU)["gyro_frd_rad_s"].astype(float)
    assert np.abs(gyro[:100]).max() < 1e-6                   # before 0.1 s
    assert gyro[150, 0] == pytest.approx(0.04, abs=1e-6)     # step on x
    assert gyro[200, 2] == pytest.approx(-0.03 * 0.5, abs=2e-4)   # ramp half way
    assert gyro[350, 2] == pytest.approx(-0.03, abs=1e-6)
    assert gyro[550, 2] == pytest.approx(0.0, abs=1e-6)      # off at 0.5 s
    assert gyro[550, 0] == pytest.approx(0.04, abs=1e-6)     # x stays
    texts = [t for _, t in sim.drain_events()]
    assert len(texts) == 3 and "on" in texts[0] and "off" in texts[2]
    assert sim.events == []


def test_s3_force_is_sinusoidal_at_the_drawn_amplitude_and_frequency():
    sc = load_scenario("S3", seed=7, overrides={"disturbance[0].start_s": 0.5,
                                                "home.initial_agl_m": 30.0})
    d = sc.disturbances[0]
    sim = Simulator(sc)
    pwm = [sim.hover_pwm_us] * 4
    fy = []
    for _ in range(500 + int(2000 / d.frequency_hz)):    # two periods
        sim.step(pwm)
        fy.append(sim.fdm.fdm["external_reactions/dist_ned/x"])
    fy = np.array(fy[500:])
    assert fy.max() == pytest.approx(sim.fdm.mass_kg * 9.80665 * d.amplitude_g, rel=1e-3)
    crossings = np.count_nonzero(np.diff(np.sign(fy[1:])) != 0)
    assert crossings in (3, 4)


def test_s5_motor_bias_switches_the_thrust_scale():
    sc = load_scenario("S5", overrides={"disturbance[0].start_s": 0.2,
                                        "disturbance[0].stop_s": 0.4})
    sim = Simulator(sc)
    scale = sc.disturbances[0].thrust_scale[0]
    assert 0.90 <= scale <= 0.97
    collect(sim, [1000] * 4, 300)
    assert sim.truth()["thrust_scale"] == (scale, 1.0, 1.0, 1.0)
    collect(sim, [1000] * 4, 200)
    assert sim.truth()["thrust_scale"] == (1.0, 1.0, 1.0, 1.0)


def test_s4_setpoints_ramps_steps_and_doublets():
    sc = load_scenario("S4", seed=11)
    prog = SetpointProgram(sc, 1_000_000, 0.0)
    ev = prog.events
    assert ev[0] == (1, 0.0, 0.0, 0.0, 10.0, 7)
    roll = np.array([e[1] for e in ev])
    pitch = np.array([e[2] for e in ev])
    amps = sc.setpoints[0].amplitude_deg + sc.setpoints[1].amplitude_deg
    assert np.degrees(max(np.abs(roll).max(), np.abs(pitch).max())) <= max(amps) + 1e-9
    assert np.degrees(roll.max()) == pytest.approx(max(sc.setpoints[0].amplitude_deg))
    assert np.degrees(pitch.min()) == pytest.approx(-max(sc.setpoints[1].amplitude_deg))
    # First roll doublet: ramp 0 -> A over 0.5 s from 10 s, emitted at 100 Hz.
    a0 = math.radians(sc.setpoints[0].amplitude_deg[0])
    # (the 0 at 10 s repeats the level setpoint, so it is not re-sent)
    ramp = [e for e in ev if 10_000 <= e[0] <= 10_500]
    assert [e[0] for e in ramp] == list(range(10_010, 10_501, 10))
    assert ramp[0][1] == pytest.approx(a0 * 0.02)
    assert ramp[-1][1] == pytest.approx(a0)
    # First pitch doublet is a step at 20 s: +A at once, level after hold, -A after
    # another hold, then level: every step is A, never 2A.
    p0 = math.radians(sc.setpoints[1].amplitude_deg[0])
    hold = sc.setpoints[1].hold_s[0]
    pitch_ev = [e for e in ev if 19_000 < e[0] < 30_000]
    def first_step_at(t_s):   # the first step whose time is at or after t_s
        return -(-round(t_s * 1e9) // 1_000_000)

    assert [e[0] for e in pitch_ev] == [20_000, first_step_at(20.0 + hold),
                                        first_step_at(20.0 + 2 * hold),
                                        first_step_at(20.0 + 3 * hold)]
    assert [e[2] for e in pitch_ev] == pytest.approx([p0, 0.0, -p0, 0.0])
    # Everything returns to level, altitude held.
    assert ev[-1][1] == 0.0 and ev[-1][2] == 0.0 and all(e[4] == 10.0 for e in ev)


def test_setpoint_records_follow_the_program():
    sc = load_scenario("S4", overrides={"setpoint[0].start_s": 0.1, "setpoint[1].start_s": 3.0})
    sim = Simulator(sc)
    sps = of_kind(collect(sim, [1000] * 4, 800), Kind.SETPOINT)
    prog = SetpointProgram(sc, sim.dt_ns, 0.0)
    expect = [e for e in prog.events if e[0] <= 800]
    assert len(sps) == len(expect)
    assert (sps["sim_ns"] == [e[0] * sim.dt_ns for e in expect]).all()
    assert np.allclose(sps["roll_rad"], [e[1] for e in expect], atol=1e-6)
    assert (sps["seq"] == np.arange(len(sps))).all()


def test_altitude_and_yaw_setpoints():
    over = {"setpoint": [{"type": "altitude", "start_s": 1.0, "altitude_m": 20.0, "ramp_s": 2.0},
                         {"type": "yaw", "start_s": 2.0, "yaw_deg": 190.0}]}
    sc = load_scenario("S1", overrides=over)
    ev = SetpointProgram(sc, 1_000_000, 0.0).events
    at = {e[0]: e for e in ev}
    assert at[2000][4] == pytest.approx(15.0)
    assert at[3000][4] == pytest.approx(20.0)
    assert at[2000][3] == pytest.approx(math.radians(-170.0))
