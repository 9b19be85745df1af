"""The GNSS epochs made in C (bridge/src/gnss_model.c, bridge/gnss_kernel.py) write the
records Python's model (bridge/lowrate.py) writes, byte for byte, and hand the model back
to Python where only Python can make the fix. Real JSBSim, the real C kernel, a flight
that takes off and flips (every record of every step compared)."""

from __future__ import annotations

import numpy as np
import pytest

from bridge_test_helpers import of_kind, take_off_and_flip
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import Kind

_NS = 1_000_000_000


def _fly(steps: int, gnss_in_c: bool, **overrides):
    """Every record of `steps` steps, and where the GNSS epochs were made at each step."""
    sim = Simulator(load_scenario("S1", overrides=overrides or None), gnss_in_c=gnss_in_c)
    recs, in_c = [], []
    for k in range(steps):
        recs.append(sim.step(take_off_and_flip(sim, k)).copy())
        in_c.append(sim.kernel.gnss_on)
    return sim, np.concatenate(recs), np.array(in_c)


def _same_records(c_recs, py_recs):
    c_gnss, py_gnss = of_kind(c_recs, Kind.GNSS), of_kind(py_recs, Kind.GNSS)
    assert len(c_gnss) == len(py_gnss)
    np.testing.assert_array_equal(c_gnss, py_gnss)       # a clear message for the fixes
    assert c_recs.tobytes() == py_recs.tobytes()          # and the whole record stream


def test_the_kernel_makes_the_fixes_python_makes():
    c_sim, c_recs, in_c = _fly(4000, True)
    py_sim, py_recs, py_in_c = _fly(4000, False)
    _same_records(c_recs, py_recs)
    assert not py_in_c.any()
    # Python releases the first fix (210 ms: epoch 100 ms + 110 ms), then the kernel makes them
    assert not in_c[:209].any() and in_c[210:].all()
    assert len(of_kind(c_recs, Kind.GNSS)) >= 38
    assert c_sim.published_counts() == py_sim.published_counts()
    # the model's state, handed back, is Python's to the last bit
    c_sim._kgnss._from_kernel()
    c, py = c_sim.gnss, py_sim.gnss
    assert (c.schedule.m, c.schedule.next_ns, c.last_epoch_ns) == \
        (py.schedule.m, py.schedule.next_ns, py.last_epoch_ns)
    assert c.err_ned_m == py.err_ned_m and c.noise.next_row() == py.noise.next_row()


def test_a_gnss_fault_takes_the_model_back_and_gives_it_again():
    failures = [{"unit": "gnss", "type": "glitch", "at_s": 1.0, "duration_s": 0.5,
                 "offset_m": [15.0, -5.0, 2.0]},
                {"unit": "gnss", "type": "sats_drop", "at_s": 2.0, "duration_s": 0.6,
                 "satellites": 5, "ramp_s": 0.3}]
    c_sim, c_recs, in_c = _fly(3200, True, failure=failures)
    _, py_recs, _ = _fly(3200, False, failure=failures)
    _same_records(c_recs, py_recs)
    steps = np.arange(1, len(in_c) + 1)        # in_c[i]: after step i + 1 (1 ms steps)
    # a fault acts on the steps after its at_s, up to its end (bridge/faults/engine.py)
    for at_ms, end_ms in ((1000, 1500), (2000, 2600)):
        assert in_c[steps == at_ms].all() and not in_c[(steps > at_ms) & (steps <= end_ms)].any()
    # back in C once the fault is over, until the next
    assert in_c[(steps > 1600) & (steps <= 2000)].all() and in_c[steps > 2700].all()


def test_a_fault_injected_between_steps_reaches_the_fixes():
    """A script's inject (MAVLink's INJECT_FAILURE, tests' scripts) switches the fault
    outside the engine's schedule: the model comes back to Python at once all the same."""
    def fly(gnss_in_c):
        sim = Simulator(load_scenario("S1"), gnss_in_c=gnss_in_c)
        recs, in_c = [], []
        for k in range(2500):
            if k in (1000, 1800):
                sim.faults.inject("gnss", "glitch", 1, {"offset_m": [30.0, 0.0, 0.0]},
                                  k == 1000, sim.sim_ns)
            recs.append(sim.step(take_off_and_flip(sim, k)).copy())
            in_c.append(sim.kernel.gnss_on)
        return np.concatenate(recs), np.array(in_c)

    c_recs, in_c = fly(True)
    py_recs, _ = fly(False)
    _same_records(c_recs, py_recs)
    assert in_c[999] and not in_c[1000:1800].any() and in_c[1900:].all()
    # the glitch shows: the fixes made under it are 30 m north of the fault-free ones
    lat = of_kind(c_recs, Kind.GNSS)["lat_e7"].astype(np.int64)
    assert np.abs(np.diff(lat)).max() > 2000           # 30 m ~ 2,700e-7 deg


def test_noise_blocks_run_out_and_are_refilled_in_c():
    # 500 Hz epochs, 4 ms latency: the 1,024-row block lasts ~2 s, so 5 s use three
    c_sim, c_recs, in_c = _fly(5000, True, **{"gnss.rate_hz": 500.0, "gnss.latency_s": 0.004})
    _, py_recs, _ = _fly(5000, False, **{"gnss.rate_hz": 500.0, "gnss.latency_s": 0.004})
    _same_records(c_recs, py_recs)
    assert in_c[100:].all()
    assert len(of_kind(c_recs, Kind.GNSS)) > 2 * 1024


@pytest.mark.parametrize("latency_s, in_c_expected, fixes", [
    (0.0, True, 30),      # each fix released at its own epoch, in C (epochs 0.1..3.0 s)
    (0.65, True, 23),     # seven fixes in flight at once: nearly all the kernel holds
    (2.0, False, 10),     # twenty in flight, more than it holds: Python keeps the model
])
def test_latencies_from_none_to_more_than_the_kernel_holds(latency_s, in_c_expected, fixes):
    c_sim, c_recs, in_c = _fly(3000, True, **{"gnss.latency_s": latency_s})
    _, py_recs, _ = _fly(3000, False, **{"gnss.latency_s": latency_s})
    _same_records(c_recs, py_recs)
    assert in_c.any() == in_c_expected
    assert len(of_kind(c_recs, Kind.GNSS)) == fixes


def test_the_kernel_refuses_to_take_the_model_unconfigured():
    sim = Simulator(load_scenario("S1"), gnss_in_c=False)
    with pytest.raises(RuntimeError, match="configure_gnss"):
        sim.kernel.gnss_take(1, None, 0, 0)
    with pytest.raises(RuntimeError, match="not on"):
        sim.kernel.gnss_give()


@pytest.mark.parametrize("block, pos, why", [
    (np.zeros((4, 5)), 0, r"GNSS noise must be \(rows, 6\) float64"),
    (np.zeros((4, 6)), 5, "GNSS noise: the first row to read must be 0..4, not 5"),
    (np.zeros((4, 6)), -1, "GNSS noise: the first row to read must be 0..4, not -1")])
def test_a_bad_noise_block_is_refused_and_the_one_before_kept(block, pos, why):
    sim = Simulator(load_scenario("S1"), gnss_in_c=False)
    sim.kernel.configure_gnss(
        rate_hz=10.0, latency_ns=0, sigma_ned_m=(1.0, 1.0, 2.0), tau_s=5.0, vel_sigma_m_s=0.1,
        m_per_rad_lat=6.4e6, m_per_rad_lon=6.4e6, ground_alt_m=0.0, eph_cm=100, epv_cm=200,
        fix_type=3, satellites=10)
    sim.kernel.set_gnss_block(np.zeros((4, 6)), 3)
    with pytest.raises(ValueError, match=why):
        sim.kernel.set_gnss_block(block, pos)
    # The kernel still holds the good block, at its row 3: the model takes it there.
    sim.kernel.gnss_take(1, None, 0, 0)
    assert sim.kernel.gnss_give()[3] == 3
