"""Motor faults of issue 28 on the real JSBSim quad (bridge/faults/motors.py): a lost motor's
thrust and the vehicle's answer to it, the ESC desync's reproducible dropouts, a damaged
prop's vibration in the vibrating world, and the product with a motor_bias disturbance.
Open loop at the hover pulse width, 10 m up (no ground in the way), short flights.
"""

from __future__ import annotations

import numpy as np

from bridge_test_helpers import of_kind
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind


def _fly(failures, steps=1000, overrides=None, seed=None):
    sc = load_scenario("S1", seed=seed, overrides={"duration_s": 2.0, "home.initial_agl_m": 10.0,
                                                   "failure": failures, **(overrides or {})})
    sim = Simulator(sc)
    rows, recs = [], []
    for _ in range(steps):
        recs.append(sim.step((sim.hover_pwm_us,) * 4).copy())
        t = sim.truth()
        rows.append((*t["thrust_scale"], *sim.thrust_n(), *t["rates_frd_rad_s"]))
    return sim, np.array(rows), np.concatenate(recs)


SCALE, THRUST, RATES = slice(0, 4), slice(4, 8), slice(8, 11)


def test_total_thrust_loss_cuts_the_motor_and_the_vehicle_rolls_and_pitches_into_it():
    _, a, _ = _fly([{"unit": "motor", "type": "thrust_loss", "instance": 1, "at_s": 0.5,
                     "remaining": 0.0}])
    _, b, _ = _fly([])
    assert (a[:500] == b[:500]).all()                    # nothing before the switch
    assert (a[500:, THRUST][:, 0] == 0).all() and (a[500:, SCALE][:, 1:] == 1).all()
    p, q, _ = a[-1, RATES]
    # Motor 1 is front right: without it the vehicle rolls right (+p) and pitches down (-q).
    assert p > 5.0 and q < -5.0
    assert np.abs(b[:, RATES]).max() < 1e-3            # the healthy quad stays level


def test_partial_loss_scales_that_rotors_thrust():
    _, a, _ = _fly([{"unit": "motor", "type": "thrust_loss", "instance": 3, "at_s": 0.2,
                     "remaining": 0.5}], steps=201)
    _, b, _ = _fly([], steps=201)
    np.testing.assert_allclose(a[200, THRUST], b[200, THRUST] * [1.0, 1.0, 0.5, 1.0], rtol=1e-12)


def test_loss_multiplies_with_a_motor_bias_disturbance():
    bias = {"disturbance": [{"type": "motor_bias", "start_s": 0.0,
                             "thrust_scale": [0.9, 1.0, 1.0, 1.0]}]}
    _, a, _ = _fly([{"unit": "motor", "type": "thrust_loss", "instance": 1, "at_s": 0.1,
                     "duration_s": 0.1, "remaining": 0.5}], steps=300, overrides=bias)
    assert a[50, 0] == 0.9 and a[150, 0] == 0.9 * 0.5 and a[250, 0] == 0.9


def _dropouts(scale):
    """(start index, length) of each run of a zero scale."""
    cut = np.concatenate([[0], (scale == 0).astype(int), [0]])
    edges = np.flatnonzero(np.diff(cut))
    return list(zip(edges[::2].tolist(), (edges[1::2] - edges[::2]).tolist()))


def test_desync_dropouts_are_reproducible_and_last_dropout_s():
    f = [{"unit": "motor", "type": "desync", "instance": 2, "at_s": 0.1, "rate_hz": 5.0,
          "dropout_s": 0.03}]
    sim, a, _ = _fly(f)
    _, again, _ = _fly(f)
    _, other_seed, _ = _fly(f, seed=2)
    drops = _dropouts(a[:, 1])
    assert len(drops) >= 2 and all(n == 30 for _, n in drops[:-1])
    assert all(start >= 100 for start, _ in drops)
    assert (a[:, [0, 2, 3]] == 1).all()
    assert drops == _dropouts(again[:, 1]) and drops != _dropouts(other_seed[:, 1])
    cuts = [t for _, t in sim.drain_events() if "cut" in t]
    assert len(cuts) == len(drops)


def test_damaged_prop_shakes_the_imu_through_the_vibration_model():
    vib = {"vibration.enabled": True}
    f = [{"unit": "motor", "type": "damaged_prop", "instance": 1, "at_s": 0.5,
          "remaining": 1.0, "imbalance_scale": 5.0}]
    _, a, ra = _fly(f, steps=700, overrides=vib)
    _, b, rb = _fly([], steps=700, overrides=vib)
    assert (a == b).all()                    # remaining 1: the same flight; only the IMU shakes
    ia, ib = of_kind(ra, Kind.IMU), of_kind(rb, Kind.IMU)
    d = ia["accel_frd_m_s2"].astype(float) - ib["accel_frd_m_s2"]
    assert (d[:500] == 0).all()
    # Rotor 1's 1/rev line grows 5x: the difference is 4x that line, more than the four
    # balanced rotors' whole vibration in the rotor plane (x, y: about 2x one line).
    ref_xy = ib["accel_frd_m_s2"][550:, :2].astype(float)
    ref_rms = np.sqrt(((ref_xy - ref_xy.mean(axis=0)) ** 2).mean())
    assert np.sqrt((d[550:, :2] ** 2).mean()) > 1.2 * ref_rms
