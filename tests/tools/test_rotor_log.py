"""The /rotor log channel (tools/logs/rotor_log.py): the motor model's rotor speeds, per
physics step, written by the bridge side of a real closed-loop flight (JSBSim + our FC)."""

import math

import numpy as np
import pytest
from mcap.reader import make_reader

from silbridge.bridge.fdm import G0_M_S2
from silbridge.bridge.scenario import load_scenario
from silbridge.bridge.simulator import Simulator
from silbridge.tools.logs.integrity import check_log
from silbridge.tools.logs.mcap_log import LogWriter, read_log
from silbridge.tools.logs.rotor_log import (ROTOR_CHANNEL, RPM_PER_RAD_S, RotorLog,
                                            RotorSpool, declare_rate)
from silbridge.tools.loop import flight


def test_rows_are_the_motor_models_omega_at_every_step(tmp_path):
    """Straight from the Simulator: each row holds JSBSim's fcs/mN-omega-rad_s after the step
    it is stamped with, and rpm is the same speed."""
    sim = Simulator(load_scenario("S1"))
    path = tmp_path / "rotor.mcap"
    truth = []
    with LogWriter(path, metadata=declare_rate({}, 1000.0), viz_hz=0) as w:
        log = RotorLog(w, sim.rotor_rad_s)
        for k in range(1, 401):
            pwm = (1300 + k, 1400, 1500 + k // 2, 1600)     # four different, moving speeds
            sim.step(pwm)
            log(sim.sim_ns)
            truth.append([h.get_double_value() for h in sim.fdm.h_omega])
    rows = read_log(path).channels[ROTOR_CHANNEL]
    assert len(rows) == 400
    np.testing.assert_array_equal(rows["sim_ns"], np.arange(1, 401) * 1_000_000)
    np.testing.assert_array_equal(rows["omega_rad_s"], np.array(truth))
    np.testing.assert_allclose(rows["rpm"], rows["omega_rad_s"] * 60.0 / (2.0 * math.pi))
    assert len(set(rows["omega_rad_s"][-1])) == 4 and rows["omega_rad_s"][-1].min() > 100.0


def test_a_logged_flight_carries_rotor_at_the_physics_rate(tmp_path):
    """fly --processes 1 --log: /rotor has a row per physics step for 4 motors, declared as
    config.rotor_hz, passes the integrity check, and in hover each rotor turns at the speed
    whose thrust carries a quarter of the weight (kT omega^2 = m g / 4)."""
    path = str(tmp_path / "s1.mcap")
    flight.fly_one_process(flight.FlightOptions(scenario="S1", duration_s=25.0, processes=1,
                                                log_path=path), out=lambda s: None)
    log = read_log(path)
    assert log.read_error is None
    assert log.metadata["config"]["rotor_hz"] == 1000.0
    assert check_log(log) == []
    rows = log.channels[ROTOR_CHANNEL]
    assert rows["omega_rad_s"].shape == (25_000, 4)
    assert set(np.diff(rows["sim_ns"]).tolist()) == {1_000_000}
    np.testing.assert_array_equal(rows["sim_ns"], log.channels["/gt_att"]["sim_ns"])
    sim = Simulator(load_scenario("S1"))
    kt = sim.fdm.model_constant("quadx/kt-n-per-rad_s2")
    hover = math.sqrt(sim.fdm.mass_kg * G0_M_S2 / (4.0 * kt))
    late = rows["omega_rad_s"][rows["sim_ns"] > 20_000_000_000]
    np.testing.assert_allclose(late.mean(axis=0), hover, rtol=0.01)
    np.testing.assert_allclose(rows["rpm"], rows["omega_rad_s"] * RPM_PER_RAD_S)
    # The Foxglove plot channel: one message per sample, here every physics step.
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    topics = {c.topic: c.id for c in summary.channels.values()}
    assert summary.statistics.channel_message_counts[topics["/viz/rotor"]] == 25_000


def test_spooled_rows_are_appended_to_a_finished_log(tmp_path):
    """The two-process path's mechanics: a finished log (another writer's) gets /rotor after
    its end; every earlier channel, event and metadata reads as before, the mcap package
    reads the new summary, and the rows are the spooled ones."""
    path = tmp_path / "fc.mcap"
    imu = np.zeros(3000, dtype=[("sim_ns", "<i8"), ("gyro", "<f8", (3,))])
    imu["sim_ns"] = np.arange(1, 3001) * 1_000_000
    imu["gyro"] = np.random.default_rng(1).standard_normal((3000, 3))
    with LogWriter(path, metadata=declare_rate({"config": {"seed": 1}}, 1000.0)) as w:
        w.write("/imu_test", imu)
        w.event(5_000_000, "mode", "takeoff")
    before = read_log(path)
    omega = [[500.0 + i, 400.0, 300.0 + i / 10, 200.0] for i in range(2500)]
    speeds = iter(omega)
    spool = RotorSpool(tmp_path / "fc.mcap.rotor.spool", lambda: next(speeds))
    for i in range(2500):
        spool.rotor((i + 1) * 1_000_000)
    assert spool.append_into(path) == 2500
    assert not (tmp_path / "fc.mcap.rotor.spool").exists()
    after = read_log(path)
    assert after.read_error is None and not after.truncated
    np.testing.assert_array_equal(after.channels["/imu_test"], before.channels["/imu_test"])
    assert after.events == before.events and after.metadata == before.metadata
    rows = after.channels[ROTOR_CHANNEL]
    np.testing.assert_array_equal(rows["omega_rad_s"], np.array(omega))
    np.testing.assert_array_equal(rows["sim_ns"], np.arange(1, 2501) * 1_000_000)
    assert check_log(after) == []
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        counts = {c.topic: summary.statistics.channel_message_counts.get(c.id, 0)
                  for c in summary.channels.values()}
        assert counts[ROTOR_CHANNEL] == 3 and counts["/imu_test"] == 3   # 1024-row batches
        n = sum(1 for _ in reader.iter_messages(topics=[ROTOR_CHANNEL]))
    assert n == 3


def test_two_process_flight_log_carries_rotor(tmp_path):
    """fly --processes 2 --log: the FC process writes the log, the bridge appends /rotor."""
    path = str(tmp_path / "p2.mcap")
    flight.fly_two_processes(flight.FlightOptions(scenario="S1", duration_s=12.0,
                                                  log_path=path), out=lambda s: None)
    log = read_log(path)
    assert log.read_error is None and check_log(log) == []
    rows = log.channels[ROTOR_CHANNEL]
    np.testing.assert_array_equal(rows["sim_ns"], log.channels["/gt_att"]["sim_ns"])
    assert rows["omega_rad_s"].shape == (12_000, 4) and rows["omega_rad_s"][-1].min() > 300
    assert not list(tmp_path.glob("*.spool"))


def test_spool_takes_a_batch_as_its_steps(tmp_path):
    """write_rows (a lockstep batch's rows at once, which lets a logged two-process flight
    keep its batches in C) spools the bytes the per-step calls would, flushes included."""
    omega = np.random.default_rng(3).uniform(0, 900, (3000, 4))
    sim_ns = np.arange(1, 3001, dtype=np.int64) * 1_000_000
    rows = iter(omega.tolist())
    per_step = RotorSpool(tmp_path / "a.spool", lambda: next(rows))
    for t in sim_ns.tolist():
        per_step.rotor(t)
    batched = RotorSpool(tmp_path / "b.spool", None)
    for at in range(0, 3000, 700):     # batches that cross the 1024-row flushes
        batched.rotor.write_rows(sim_ns[at:at + 700], omega[at:at + 700])
    per_step.close()
    batched.close()
    assert (tmp_path / "a.spool").read_bytes() == (tmp_path / "b.spool").read_bytes()


def test_log_writer_takes_rows_as_packs(tmp_path):
    """LogWriter.pack_rows: the same /rotor rows as one pack() per step, and a wrong dtype
    is refused."""
    omega = np.random.default_rng(4).uniform(0, 900, (1500, 4))
    sim_ns = np.arange(1, 1501, dtype=np.int64) * 1_000_000
    logs = []
    for batched in (False, True):
        path = tmp_path / f"{batched}.mcap"
        with LogWriter(path, metadata=declare_rate({"config": {"seed": 1}}, 1000.0)) as w:
            it = iter(omega.tolist())
            log = RotorLog(w, lambda: next(it))
            if batched:
                log.write_rows(sim_ns, omega)
                with pytest.raises(ValueError, match="dtype"):
                    w.pack_rows(ROTOR_CHANNEL, np.zeros(3))
            else:
                for t in sim_ns.tolist():
                    log(t)
        logs.append(read_log(path).channels[ROTOR_CHANNEL])
    np.testing.assert_array_equal(logs[0], logs[1])
