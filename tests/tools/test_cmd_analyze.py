"""`silbridge analyze`: metrics of a good log; one-line refusal of a bad one."""

import json
import subprocess
import sys

import pytest

from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter


def _analyze(*args):
    return subprocess.run([sys.executable, "-m", "silbridge.tools", "analyze", *map(str, args)],
                          capture_output=True, text=True, timeout=60)


@pytest.fixture(scope="module")
def good_log(tmp_path_factory):
    run = synthetic_run(6.0, roll_err_amp_deg=2.0, pwm_amp_us=10.0)
    path = tmp_path_factory.mktemp("logs") / "good.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    return path


def test_json_output_is_one_object(good_log):
    proc = _analyze(good_log, "--json", "--analysis", 2, 6, "--yaw-window", 4, 6)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["ok"] is True and out["problems"] == []
    m = out["metrics"]
    assert m["pwm_pp_us"] == pytest.approx(20.0)
    assert m["att_rms_deg"] == pytest.approx(2.0 / 2 ** 0.5, rel=5e-3)
    assert out["windows"]["analysis"] == [2.0, 6.0]
    assert out["integrity"]["channels"]["/imu"]["rows"] == 6000


def test_text_table(good_log):
    proc = _analyze(good_log)
    assert proc.returncode == 0, proc.stderr
    assert "attitude error RMS" in proc.stdout and "PWM peak-to-peak" in proc.stdout
    assert "note: log ends at 6.000 s" in proc.stdout


def test_log_missing_whole_channels_is_refused_in_one_line(good_log, tmp_path):
    """Cut at half a log written channel after channel: configured channels have no rows at
    all, which no killed run explains (every channel is flushed every half second)."""
    data = good_log.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    proc = _analyze(cut)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "fails the integrity check: " in lines[0] and "no rows" in lines[0]
    # --json still prints the problems as one object; --force analyses anyway.
    proc = _analyze(cut, "--json")
    assert proc.returncode == 2
    problems = json.loads(proc.stdout)["problems"]
    assert any("no rows, but the run config sets" in p for p in problems)
    proc = _analyze(cut, "--force", "--json")
    assert proc.returncode == 0 and json.loads(proc.stdout)["ok"] is False


def test_unfinished_log_of_a_killed_run_is_analyzed_up_to_its_end(tmp_path):
    """A writer killed mid-run (file cut inside a record, no summary): analyze reads it
    without --force, says where each channel ends, and computes the metrics over it."""
    from silbridge.tools.logs.log_synth import step_slices

    run = synthetic_run(6.0, roll_err_amp_deg=2.0, pwm_amp_us=10.0)
    path = tmp_path / "whole.mcap"
    w = LogWriter(path, metadata=run.metadata, batch_rows=128)
    for step in step_slices(run):          # as a run logs: all channels, step by step
        for name, rows in step.items():
            if len(rows):
                w.write(name, rows)        # every 0.5 s of sim time: a flush of all channels
    data = path.read_bytes()               # no close(): the writer "was killed"
    w._mcap.close()
    cut = tmp_path / "killed.mcap"
    cut.write_bytes(data[: int(len(data) * 0.7) + 5])   # and inside a record
    proc = _analyze(cut, "--json", "--analysis", 1, 6)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = json.loads(proc.stdout)
    assert out["ok"] is True
    unfinished = out["integrity"]["unfinished"]
    assert unfinished["reason"].startswith("the writer never finished")
    assert unfinished["planned_s"] == pytest.approx(6.0)
    imu = unfinished["channels"]["/imu"]
    assert 1.0 < imu["last_s"] < 6.0
    assert imu["missing_s"] == pytest.approx(6.0 - imu["last_s"])
    assert out["metrics"]["att_rms_deg"] == pytest.approx(2.0 / 2 ** 0.5, rel=0.05)
    text = _analyze(cut).stdout
    assert "missing at the end (of 6 s planned)" in text and "/imu" in text


def test_damaged_log_still_needs_force(tmp_path):
    # Without the viewable /viz channels, which the analysis skips unread, so the flipped
    # byte lands inside an analysis batch whatever the log's layout.
    run = synthetic_run(6.0, roll_err_amp_deg=2.0, pwm_amp_us=10.0)
    plain = tmp_path / "plain.mcap"
    with LogWriter(plain, metadata=run.metadata, viz_hz=0) as w:
        write_run(run, w)
    data = bytearray(plain.read_bytes())
    data[len(data) // 3] ^= 0xFF          # a flipped byte inside a batch: its CRC fails
    bad = tmp_path / "damaged.mcap"
    bad.write_bytes(bytes(data))
    proc = _analyze(bad)
    assert proc.returncode == 2 and "corrupt" in proc.stderr
    assert _analyze(bad, "--force").returncode == 0


def test_not_a_log_is_refused(tmp_path):
    bad = tmp_path / "x.mcap"
    bad.write_bytes(b"\x00" * 100)
    proc = _analyze(bad)
    assert proc.returncode == 2 and "not an MCAP file" in proc.stderr


def test_bad_window_is_refused(good_log):
    proc = _analyze(good_log, "--analysis", 30, 10)
    assert proc.returncode == 2 and "window analysis must end after it starts" in proc.stderr
