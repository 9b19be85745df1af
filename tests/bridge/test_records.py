"""Record stream contract: order within a step, STEP_END, sim_ns, seq, setpoints."""

import numpy as np

from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.shm.records import FLAG_STEP_END, RECORD_DTYPE, Kind

from bridge_test_helpers import of_kind

ORDER = [Kind.IMU, Kind.GT_ATT, Kind.GT_NAV, Kind.BARO, Kind.MAG, Kind.GNSS, Kind.SETPOINT,
         Kind.BATTERY, Kind.ESC]


def test_step_order_flags_times_and_seq():
    sim = Simulator(load_scenario("S1"), imu_hz=4000)
    last_seq = {}
    for k in range(1, 1201):
        recs = sim.step([1000] * 4)
        assert recs.dtype == RECORD_DTYPE
        kinds = [Kind(x) for x in recs["kind"]]
        assert kinds == sorted(kinds, key=ORDER.index)
        assert kinds.count(Kind.IMU) == 4 and kinds.count(Kind.GT_ATT) == 1
        assert kinds.count(Kind.GT_NAV) == 1
        assert recs["flags"].tolist() == [0] * (len(recs) - 1) + [FLAG_STEP_END]
        assert (recs["wall_ns"] == 0).all()
        non_imu = recs[recs["kind"] != int(Kind.IMU)]
        assert (non_imu["sim_ns"] == k * sim.dt_ns).all() and sim.sim_ns == k * sim.dt_ns
        assert sim.step_index == k
        for kind in set(kinds):
            for s in recs[recs["kind"] == int(kind)]["seq"]:
                assert s == last_seq.get(kind, -1) + 1
                last_seq[kind] = s
    # 1.2 s: 120 baro and mag samples; GNSS epochs 0.1..1.2 s released 110 ms later -> 10.
    assert last_seq[Kind.BARO] == 119 and last_seq[Kind.MAG] == 119
    assert last_seq[Kind.GNSS] == 9
    counts = sim.published_counts()
    assert counts["imu"] == 4800 and counts["baro"] == 120 and counts["gnss"] == 10
    assert counts["gt_att"] == counts["gt_nav"] == 1200 and counts["setpoint"] == 1
    assert last_seq[Kind.BATTERY] == 11 and counts["battery"] == 12     # 10 Hz, 0.1..1.2 s


def test_records_are_a_view_valid_until_the_next_step():
    sim = Simulator(load_scenario("S1"))
    a = sim.step([1000] * 4)
    kept = a.copy()
    sim.step([1000] * 4)
    assert not np.array_equal(a, kept)       # the buffer was reused
    assert kept["sim_ns"][0] == sim.dt_ns


def test_first_setpoint_is_the_take_off_altitude():
    sc = load_scenario("S1", overrides={"takeoff_alt_m": 12.5, "home.heading_deg": 270.0})
    sim = Simulator(sc)
    recs = sim.step([1000] * 4)
    sp = of_kind(recs, Kind.SETPOINT)
    assert len(sp) == 1 and sp["seq"][0] == 0 and sp["sim_ns"][0] == sim.dt_ns
    assert sp["altitude_m"][0] == 12.5
    assert sp["roll_rad"][0] == 0 and sp["pitch_rad"][0] == 0
    assert np.isclose(sp["yaw_rad"][0], -np.pi / 2)
    assert sp["mask"][0] == 7
    assert recs["flags"][-1] == FLAG_STEP_END and recs["kind"][-1] == int(Kind.SETPOINT)
    for _ in range(3000):                    # S1 never changes it again
        assert not (sim.step([1000] * 4)["kind"] == int(Kind.SETPOINT)).any()


def test_ground_truth_records_match_truth():
    sc = load_scenario("S1", overrides={"home.initial_agl_m": 20.0, "home.heading_deg": 30.0})
    sim = Simulator(sc)
    for _ in range(300):
        recs = sim.step([sim.hover_pwm_us + 20, sim.hover_pwm_us, sim.hover_pwm_us,
                         sim.hover_pwm_us])
    t = sim.truth()
    att = of_kind(recs, Kind.GT_ATT)[0]
    nav = of_kind(recs, Kind.GT_NAV)[0]
    q = np.array(t["q_wxyz"])
    assert np.allclose(att["q_wxyz"], q, atol=1e-6) and q[0] >= 0
    assert abs(np.linalg.norm(att["q_wxyz"]) - 1) < 1e-6
    assert np.allclose(att["rates_frd_rad_s"], t["rates_frd_rad_s"], atol=1e-6)
    assert np.allclose(nav["pos_ned_m"], t["pos_ned_m"], atol=5.01e-4)   # down in whole mm (HIL)
    assert np.allclose(nav["vel_ned_m_s"], t["vel_ned_m_s"], atol=5.01e-3)   # whole cm/s (HIL)
    assert nav["on_ground"] == 0
    # Quaternion of yaw 30 deg: w = cos 15 deg, z = sin 15 deg (roll/pitch small here).
    assert abs(att["q_wxyz"][0] - np.cos(np.radians(15))) < 1e-2
