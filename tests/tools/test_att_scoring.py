"""The two attitude scorings (tools/benchmark/att_scoring.py) on synthetic logs with known answers.

The synthetic run's true roll is 5 deg + 3 sin(pi t) deg and its /fc/status
target 5 deg (our FC's shaped target). A scenario command of 0 deg on
/setpoint makes the two scorings differ by a known amount; an external FC's
/fc/target reports, stamped on its own clock and read late, must be placed on
the physics clock by their stamps.
"""

import math

import numpy as np
import pytest

from silbridge.shm.records import Kind
from silbridge.tools.benchmark.att_scoring import target_clock_offset_ns
from silbridge.tools.logs.fc_target import FC_TARGET_DTYPE, TARGET_CHANNEL, CommandLog, TargetFeed
from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter, read_log
from silbridge.tools.benchmark.metrics import Windows, compute_metrics

WIN = Windows(warmup=(0, 1), transient=(1, 2), analysis=(2, 12), yaw=(8, 12))
AMP, CMD = 3.0, 5.0


def _write(tmp_path, *, fc=None, command_deg=0.0, target_rows=None):
    run = synthetic_run(12.0, roll_cmd_deg=CMD, roll_err_amp_deg=AMP, roll_err_hz=0.5)
    if fc is not None:
        run.metadata["config"]["fc"] = fc
    path = tmp_path / "s.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
        CommandLog(w).write(0, math.radians(command_deg), 0.0, 0.0, 10.0)
        if target_rows is not None:
            w.declare(TARGET_CHANNEL, FC_TARGET_DTYPE)
            feed = TargetFeed()
            for row in target_rows:
                feed.put(*row)
            feed.drain(w, 0)
    return read_log(path)


def test_our_fc_scored_against_the_command_and_its_own_target(tmp_path):
    m = compute_metrics(_write(tmp_path), WIN)
    # Against its target (5 deg): e = 3 |sin| deg. Against the command (0): 5 + 3 sin.
    assert m["att_rms_target_deg"] == pytest.approx(AMP / math.sqrt(2), rel=2e-3)
    assert m["att_rms_cmd_deg"] == pytest.approx(math.sqrt(CMD ** 2 + AMP ** 2 / 2), rel=2e-3)
    assert m["att_max_cmd_deg"] == pytest.approx(CMD + AMP, rel=1e-3)
    assert m["att_p95_cmd_deg"] > m["att_p95_target_deg"]
    # Table 1's headline is the command scoring.
    assert m["att_rms_deg"] == m["att_rms_cmd_deg"] and m["att_p95_deg"] == m["att_p95_cmd_deg"]


def test_external_target_is_placed_by_its_stamp_not_its_arrival(tmp_path):
    # The FC reports its target = the true roll at 50 Hz on a clock 7 s ahead of ours;
    # each report is read 0..40 ms of physics time late (the soonest exactly on time).
    rng = np.random.default_rng(3)
    rows = []
    for k, t_ns in enumerate(range(20_000_000, 12_000_000_000, 20_000_000)):
        roll = math.radians(CMD + AMP * math.sin(math.pi * t_ns * 1e-9))
        late = 0 if k == 10 else int(rng.integers(0, 40)) * 1_000_000
        rows.append((t_ns + late, t_ns + 7_000_000_000, roll, 0.0, 0.0))
    rows.sort()
    log = _write(tmp_path, fc="px4", target_rows=rows)
    assert target_clock_offset_ns(log) == -7_000_000_000
    m = compute_metrics(log, WIN)
    assert m["att_rms_target_deg"] < 0.01          # it tracks its own target exactly
    assert m["att_rms_cmd_deg"] == pytest.approx(math.sqrt(CMD ** 2 + AMP ** 2 / 2), rel=2e-3)
    # Placed by arrival instead, the 0..40 ms lag on a 3 deg, 0.5 Hz sine would show.
    tg = log.channels[TARGET_CHANNEL]
    lag_ms = (tg["sim_ns"] - tg["fc_time_ns"] - target_clock_offset_ns(log)) / 1e6
    assert lag_ms.max() > 30 and lag_ms.min() == 0


def test_external_fc_without_a_target_channel_is_not_scored_against_its_status(tmp_path):
    m = compute_metrics(_write(tmp_path, fc="ardupilot"), WIN)
    assert math.isnan(m["att_rms_target_deg"]) and math.isnan(m["att_p95_target_deg"])
    assert math.isfinite(m["att_rms_cmd_deg"])


def test_feed_keeps_reports_of_the_log_window_only(tmp_path):
    feed = TargetFeed()
    for rx in (5, 10, 15, 25):
        feed.put(rx, rx + 100, 0.1, 0.0, 0.0)
    feed.put(30, 130, math.nan, 0.0, 0.0)           # a broken report is dropped
    with LogWriter(tmp_path / "f.mcap", metadata={"config": {}}) as w:
        w.declare(TARGET_CHANNEL, FC_TARGET_DTYPE)
        feed.drain(w, 10, 20)
    tg = read_log(tmp_path / "f.mcap").channels[TARGET_CHANNEL]
    assert tg["sim_ns"].tolist() == [0, 5] and tg["fc_time_ns"].tolist() == [110, 115]
    assert feed.count == 2


def test_command_log_writes_setpoint_records_on_change_only(tmp_path):
    with LogWriter(tmp_path / "c.mcap", metadata={"config": {}}) as w:
        log = CommandLog(w)
        for t in range(0, 10):
            log.write(t * 1_000_000, 0.1 if t >= 5 else 0.0, 0.0, 0.0, 10.0)
    sp = read_log(tmp_path / "c.mcap").channels["/setpoint"]
    assert sp["sim_ns"].tolist() == [0, 5_000_000] and sp["seq"].tolist() == [0, 1]
    assert sp["roll_rad"].tolist() == pytest.approx([0.0, 0.1])
    assert (sp["kind"] == Kind.SETPOINT).all() and (sp["mask"] == 7).all()


def test_our_fc_s4_rows_are_scored_from_its_log_like_any_fc(tmp_path):
    """A real S4 flight of our FC: both scorings recomputed by hand from its log's
    /setpoint (command), /fc/status att_target_rad (its shaped target) and /gt_att."""
    from silbridge.tools.benchmark.att_scoring import roll_pitch_from_quat
    from silbridge.tools.benchmark.campaign import make_specs, run_one

    spec = make_specs(["S4"], 1, 17.0, tmp_path, windows=((0, 10), (10, 17), (10, 17),
                                                          (10, 17)))[0]
    r = run_one(spec)
    log = read_log(spec.log_path)
    st = log.channels["/fc/status"]
    st = st[(st["sim_ns"] >= 10e9) & (st["sim_ns"] <= 17e9)]
    gt = log.channels["/gt_att"]
    roll, pitch = roll_pitch_from_quat(
        gt["q_wxyz"][np.searchsorted(gt["sim_ns"], st["sim_ns"], side="right") - 1])
    sp = log.channels["/setpoint"]
    cmd = sp[np.searchsorted(sp["sim_ns"], st["sim_ns"], side="right") - 1]
    e_cmd = np.degrees(np.hypot(cmd["roll_rad"] - roll, cmd["pitch_rad"] - pitch))
    tgt = st["att_target_rad"].astype(np.float64)
    e_tgt = np.degrees(np.hypot(tgt[:, 0] - roll, tgt[:, 1] - pitch))
    m = r.metrics
    assert m["att_rms_cmd_deg"] == pytest.approx(np.sqrt(np.mean(e_cmd ** 2)), rel=1e-4)
    assert m["att_p95_target_deg"] == pytest.approx(np.percentile(e_tgt, 95), rel=1e-4)
    # The doublet's roll ramp is shaped: the command leads the shaped target.
    assert m["att_rms_cmd_deg"] > m["att_rms_target_deg"] > 0
    assert m["realtime_factor"] > 0
