"""The imperfect vehicle ([vehicle], bridge/vehicle_draw.py, bridge/fdm.py): per-seed draws
within the declared tolerances, applied to the real JSBSim model, and what the FC must do
about them in a real closed-loop hover."""

import math
from pathlib import Path

import numpy as np
import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.fdm import SLUG_KG
from silbridge.bridge.scenario import SCENARIO_DIR, load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.bridge.vehicle_draw import NEUTRAL, draw_vehicle
from silbridge.tools.logs.mcap_log import read_log
from silbridge.tools.loop import flight

IN_M = 0.0254


def _on(seed=1, **tol):
    over = {"vehicle.imperfect": True, **{f"vehicle.{k}": v for k, v in tol.items()}}
    return load_scenario("S1", seed=seed, overrides=over)


def _scenario_file(tmp_path: Path, vehicle: str, base: str = "S1") -> str:
    path = tmp_path / f"{base}_vehicle.toml"
    path.write_text((SCENARIO_DIR / f"{base}.toml").read_text() + "\n[vehicle]\n" + vehicle)
    return str(path)


def test_off_by_default_and_neutral():
    for name in ("S1", "S2", "S3", "S4"):
        assert draw_vehicle(load_scenario(name)) is NEUTRAL


def test_draws_differ_between_seeds_repeat_per_seed_and_stay_within_tolerance():
    a, b, a2 = draw_vehicle(_on(1)), draw_vehicle(_on(2)), draw_vehicle(_on(1))
    assert a == a2
    for field in ("cg_offset_frd_m", "kt_scale", "kq_scale", "tilt_frd_rad", "imu_rpy_rad"):
        assert getattr(a, field) != getattr(b, field), field
    sec = _on(1).vehicle
    for v in (a, b):
        assert all(abs(c) <= sec.cg_tol_xy_m for c in v.cg_offset_frd_m[:2])
        assert abs(v.cg_offset_frd_m[2]) <= sec.cg_tol_z_m
        assert all(abs(s - 1.0) <= sec.kt_tol for s in v.kt_scale)
        assert all(abs(s - 1.0) <= sec.kq_tol for s in v.kq_scale)
        assert np.abs(np.degrees(v.tilt_frd_rad)).max() <= sec.tilt_tol_deg
        assert np.abs(np.degrees(v.imu_rpy_rad)).max() <= sec.imu_tilt_tol_deg
        for d in v.thrust_dir_frd:
            assert math.isclose(np.linalg.norm(d), 1.0, rel_tol=1e-12) and d[2] < -0.99
        r = np.array(v.imu_rot)
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert not v.imu_identity


def test_one_tolerance_does_not_move_the_other_draws():
    """Each quantity has its own stream: zeroing the tilts leaves the CG and kT draws."""
    a, b = draw_vehicle(_on(3)), draw_vehicle(_on(3, tilt_tol_deg=0.0))
    assert a.cg_offset_frd_m == b.cg_offset_frd_m and a.kt_scale == b.kt_scale
    assert b.thrust_dir_frd == ((0.0, 0.0, -1.0),) * 4


@pytest.mark.parametrize("key,value,why", [
    ("vehicle.kt_tol", -0.01, ">= 0"), ("vehicle.cg_tol_xy_m", -0.001, ">= 0"),
    ("vehicle.tilt_tol_deg", -1.0, ">= 0"), ("vehicle.bent_arm", 1.0, "unknown key")])
def test_bad_input_names_the_key(key, value, why):
    with pytest.raises(ScenarioError, match=key.replace(".", r"\.") + ".*" + why):
        load_scenario("S1", overrides={key: value})


def test_the_draw_reaches_jsbsim():
    """CG where drawn with the mass unchanged, per-motor coefficients, thrust directions."""
    sim = Simulator(_on(5))
    v, f = sim.vehicle, sim.fdm.fdm
    sim.step((1000, 1000, 1000, 1000))
    cg_frd = (-f["inertia/cg-x-in"] * IN_M, f["inertia/cg-y-in"] * IN_M,
              -f["inertia/cg-z-in"] * IN_M)
    np.testing.assert_allclose(cg_frd, v.cg_offset_frd_m, atol=1e-12)
    assert math.isclose(f["inertia/mass-slugs"] * SLUG_KG, 1.5, rel_tol=1e-7)
    for i in range(4):
        assert f[f"fcs/m{i + 1}-kt-scale"] == v.kt_scale[i]
        assert f[f"fcs/m{i + 1}-kq-scale"] == v.kq_scale[i]
        assert tuple(f[f"external_reactions/m{i + 1}/{a}"] for a in "xyz") == v.thrust_dir_frd[i]
    # Thrust of each motor at one rotor speed differs as its kT does.
    for _ in range(400):
        sim.step((1500, 1500, 1500, 1500))
    thrust = np.array(sim.thrust_n())
    np.testing.assert_allclose(thrust / thrust.mean(), np.array(v.kt_scale) / np.mean(v.kt_scale),
                               rtol=1e-9)


def _fly(tmp_path, scenario: str, name: str, duration_s: float = 40.0, seed=None) -> dict:
    path = str(tmp_path / f"{name}.mcap")
    summary = flight.fly_one_process(
        flight.FlightOptions(scenario=scenario, duration_s=duration_s, processes=1,
                             log_path=path, seed=seed), out=lambda s: None)
    return summary, read_log(path)


def test_same_seed_same_trace_hash_and_seeds_differ(tmp_path):
    sc = _scenario_file(tmp_path, "imperfect = true\n")
    a, _ = _fly(tmp_path, sc, "a", 15.0)
    b, _ = _fly(tmp_path, sc, "b", 15.0)
    c, _ = _fly(tmp_path, sc, "c", 15.0, seed=7)
    assert a["trace_hash"] == b["trace_hash"] != c["trace_hash"]


def test_a_forward_right_cg_needs_front_right_motors_to_work_harder(tmp_path):
    """Only the CG off centre: in a steady hover the FC's mixer holds a pitch-up (front
    motors up) offset for a CG forward, a roll-left (right motors up) one for a CG right,
    of the size the moment balance predicts: m g d = 4 arm dT."""
    seed = next(s for s in range(1, 50)
                if all(abs(c) > 0.003 for c in draw_vehicle(_on(s)).cg_offset_frd_m[:2]))
    sc = _scenario_file(tmp_path, "imperfect = true\nkt_tol = 0.0\nkq_tol = 0.0\n"
                        "tilt_tol_deg = 0.0\nimu_tilt_tol_deg = 0.0\ncg_tol_z_m = 0.0\n")
    _, log = _fly(tmp_path, sc, "cg", seed=seed)
    dx, dy, _ = draw_vehicle(_on(seed, tilt_tol_deg=0.0)).cg_offset_frd_m
    assert log.metadata["vehicle"]["cg_offset_frd_m"] == [dx, dy, 0.0]   # published in the log
    st = log.channels["/fc/status"]
    late = st[st["sim_ns"] > 30_000_000_000]
    cp, cr = float(late["cp_us"].mean()), float(late["cr_us"].mean())
    assert np.sign(cp) == np.sign(dx) and np.sign(cr) == -np.sign(dy)
    # Predicted: per-motor thrust change m g d / (4 arm), over dT/dPWM at hover.
    sim = Simulator(load_scenario("S1"))
    arm, e = 0.1591, sim.fdm.model_constant("quadx/thrust-expo")
    dthrust_dus = sim.max_thrust_n / 4.0 * ((1 - e) + 2 * e * sim.hover_throttle) / 1000.0
    mg = sim.fdm.mass_kg * 9.80665
    assert cp == pytest.approx(mg * dx / (4 * arm) / dthrust_dus, rel=0.3)
    assert cr == pytest.approx(-mg * dy / (4 * arm) / dthrust_dus, rel=0.3)
    # The motors the FC drives harder: front for pitch, right for roll, by the PWM it sent.
    pwm = log.channels["/pwm"]
    us = pwm["pwm_us"][pwm["sim_ns"] > 30_000_000_000].mean(axis=0)
    front, back = us[[0, 2]].mean(), us[[1, 3]].mean()
    right, left = us[[0, 3]].mean(), us[[1, 2]].mean()
    assert np.sign(front - back) == np.sign(dx) and np.sign(right - left) == np.sign(dy)
