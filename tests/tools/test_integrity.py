"""Integrity check: a clean log passes; cut, lossy, disordered or failed runs are named."""

import numpy as np
import pytest

from silbridge.tools.logs.integrity import check_log, inspect_log
from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter, read_log


def _log(tmp_path, run, name="run.mcap", **kw):
    path = tmp_path / name
    with LogWriter(path, metadata=run.metadata, batch_rows=256, **kw) as w:
        write_run(run, w)
    return read_log(path)


@pytest.fixture(scope="module")
def run():
    return synthetic_run(4.0, seed=1)


def test_clean_log_passes(tmp_path, run):
    report = inspect_log(_log(tmp_path, run))
    assert report.problems == [] and report.ok
    imu = report.channels["/imu"]
    assert imu.expected == imu.rows == 4000
    assert imu.missing == 0 and imu.seq_lost == 0 and imu.loss_pct == 0.0
    assert imu.effective_hz == pytest.approx(1000.0)
    assert report.channels["/fc/status"].expected == 1600


def test_truncated_log_reports_missing_samples(tmp_path, run):
    path = tmp_path / "whole.mcap"
    with LogWriter(path, metadata=run.metadata, batch_rows=256) as w:
        for name in ("/imu", "/gt_att", "/fc/status"):
            w.write(name, run.channels[name])
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    log = read_log(cut)
    report = inspect_log(log)
    # An unfinished log: each channel is checked up to its own end, and what is missing at
    # the end is reported per channel (not as a problem).
    assert report.unfinished["reason"].startswith("the writer never finished")
    imu = report.channels["/imu"]
    assert imu.rows < 4000 and not imu.missing
    end = report.unfinished["channels"]["/imu"]
    assert end["missing_s"] == pytest.approx(4.0 - end["last_s"])
    # Channels configured but absent from what is left are problems.
    assert "/baro: no rows, but the run config sets 100 Hz" in " ".join(report.problems)


def test_sequence_gaps_count_as_loss(tmp_path):
    run = synthetic_run(4.0, seed=1)
    imu = run.channels["/imu"]
    keep = np.ones(len(imu), bool)
    keep[1000:1040] = False          # 40 of 4000 lost: 1 %
    run.channels["/imu"] = imu[keep]
    report = inspect_log(_log(tmp_path, run))
    s = report.channels["/imu"]
    assert s.seq_lost == 40 and s.missing == 40 and s.loss_pct == pytest.approx(1.0)
    assert any("/imu: 40 samples lost between sequence numbers" in p for p in report.problems)
    # Within the paper's 0.5 % the same log passes.
    assert check_log(read_log(tmp_path / "run.mcap"), max_loss_pct=2.0) == []


def test_time_going_backwards_is_named(tmp_path):
    run = synthetic_run(2.0, seed=1)
    st = run.channels["/fc/status"]
    st["sim_ns"][100], st["sim_ns"][101] = st["sim_ns"][101], st["sim_ns"][100]
    problems = check_log(_log(tmp_path, run))
    assert any(p.startswith("/fc/status: sim time does not increase 1 times") for p in problems)


def test_repeated_sequence_numbers_are_named(tmp_path):
    run = synthetic_run(2.0, seed=1)
    run.channels["/baro"]["seq"][50] = run.channels["/baro"]["seq"][49]
    problems = check_log(_log(tmp_path, run))
    assert any("/baro: sequence number repeats" in p for p in problems)


def test_wrong_rate_is_named(tmp_path):
    run = synthetic_run(2.0, seed=1)
    run.metadata["config"]["baro_hz"] = 50.0
    problems = check_log(_log(tmp_path, run))
    assert any(p.startswith("/baro: 200 samples, 100 more than the 100") for p in problems)
    assert any("/baro: effective rate 100.0 Hz is off the configured 50 Hz" in p
               for p in problems)


def test_failed_run_check_is_named(tmp_path):
    run = synthetic_run(2.0, seed=1)
    run.events.append((int(1.5e9), "check", "pwm rate 311 Hz, want 400", {"ok": False}))
    problems = check_log(_log(tmp_path, run))
    assert problems == ["run check failed at 1.500 s: pwm rate 311 Hz, want 400"]
    run.events[-1] = (int(1.5e9), "check", "rates      FAILED  pwm 311 Hz", {})
    run.events.append((int(1.6e9), "check", "drops      ok  0.0 %", {}))
    problems = check_log(_log(tmp_path, run, name="text.mcap"))
    assert problems == ["run check failed at 1.500 s: rates      FAILED  pwm 311 Hz"]


def test_log_without_closing_summary_is_named(tmp_path, run):
    log = _log(tmp_path, run)
    log.end = None
    report = inspect_log(log)
    assert report.problems == []          # unfinished, not damaged: fit for analysis
    assert report.notes == ["log unfinished: the writer never finished (no closing summary); "
                            "metrics cover what it holds"]
    assert report.unfinished["channels"]["/imu"]["last_s"] == pytest.approx(4.0)


def test_run_interrupted_before_its_first_sample_passes(tmp_path, run):
    """Ctrl-C can reach a campaign's second worker while it still starts up: its log holds
    the start metadata and no rows. Nothing was owed, so nothing is a problem; the notes say
    why it is empty. A run stopped later still owes every stream up to the stop."""
    path = tmp_path / "empty.mcap"
    LogWriter(path, metadata=run.metadata).close(interrupted="SIGINT")
    report = inspect_log(read_log(path))
    assert report.problems == []
    assert "/imu: no rows (the run ended within its first samples)" in report.notes
    assert report.notes[0] == "run interrupted by SIGINT at 0.000 s of sim time (planned 4 s)"

    # GNSS at 10 Hz stopped at 0.25 s: its first fix may still be in flight (rounding slack)
    gnss = tmp_path / "gnss.mcap"
    with LogWriter(gnss, metadata=run.metadata) as w:
        for name in ("/imu", "/gt_att"):
            w.write(name, run.channels[name][:250])
    log = read_log(gnss)
    log.end["interrupted"] = "SIGINT"
    log.end["end_sim_ns"] = 250_000_000
    problems = inspect_log(log).problems
    assert not [p for p in problems if p.startswith("/gnss")], problems
    assert "/baro: no rows, but the run config sets 100 Hz" in problems

    late = tmp_path / "late.mcap"
    with LogWriter(late, metadata=run.metadata) as w:
        w.write("/imu", run.channels["/imu"][:2000])
    log = read_log(late)
    log.end["interrupted"] = "SIGINT"
    assert "/baro: no rows, but the run config sets 100 Hz" in inspect_log(log).problems
