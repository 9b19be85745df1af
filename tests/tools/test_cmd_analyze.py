"""`silbridge analyze`: metrics of a good log; one-line refusal of a bad one."""

import json
import subprocess
import sys

import pytest

from silbridge.tools.log_synth import synthetic_run, write_run
from silbridge.tools.mcap_log import LogWriter


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


def test_truncated_log_is_refused_in_one_line(good_log, tmp_path):
    data = good_log.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    proc = _analyze(cut)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "fails the integrity check: log is cut short" in lines[0]
    # --json still prints the problems as one object; --force analyses anyway.
    proc = _analyze(cut, "--json")
    assert proc.returncode == 2
    problems = json.loads(proc.stdout)["problems"]
    assert any("expected samples" in p for p in problems)
    proc = _analyze(cut, "--force", "--json")
    assert proc.returncode == 0 and json.loads(proc.stdout)["ok"] is False


def test_not_a_log_is_refused(tmp_path):
    bad = tmp_path / "x.mcap"
    bad.write_bytes(b"\x00" * 100)
    proc = _analyze(bad)
    assert proc.returncode == 2 and "not an MCAP file" in proc.stderr


def test_bad_window_is_refused(good_log):
    proc = _analyze(good_log, "--analysis", 30, 10)
    assert proc.returncode == 2 and "window analysis must end after it starts" in proc.stderr
