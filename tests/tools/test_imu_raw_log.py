"""/imu_raw in a real flight's log (JSBSim + our FC, one process, lockstep, 12 s of sim
time): present at the chip's data rate only when the scenario asks for it, declared in the
start metadata and passing the integrity check; the FC's /imu identical with it on or off;
`analyze --spectrum` gives it its own block, whose peaks sit at k x the rotor frequency
within 1 %, and a 15th-order line (~1.2 kHz, above the FC's 500 Hz Nyquist) at its true
frequency there, where the FC's /imu shows its alias (marked as such)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from silbridge.tools.logs.imu_raw_log import RATE_KEY, RAW_IMU_CHANNEL
from silbridge.tools.logs.integrity import check_log
from silbridge.tools.logs.log_reader import read_log
from silbridge.tools.logs.spectrum_alias import fold_hz

SCENARIO = """\
name = "RAW"
description = "hover at 3 m, motor 1 prop bent, hard mount (raw chip samples test)"
seed = 1
duration_s = 12.0
takeoff_alt_m = 3.0
[windows]
warmup_s = 1.0
transient_end_s = 2.0
[vibration]
enabled = true
imbalance_scale = [5.0, 1.0, 1.0, 1.0]
harmonic_orders = [3.0, 4.0, 15.0, 0.0]
harmonic_ripple = [0.005, 0.005, 0.05, 0.0]
[mount]
type = "hard"
[imu_chip]
odr_hz = 8000
log_raw = {log_raw}
"""
HOVER = ("8", "12")


def _silbridge(*args, timeout=180):
    return subprocess.run([sys.executable, "-m", "silbridge.tools", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout)


def _fly(d, log_raw: bool):
    toml = d / f"raw_{log_raw}.toml"
    toml.write_text(SCENARIO.format(log_raw=str(log_raw).lower()))
    log = d / f"raw_{log_raw}.mcap"
    proc = _silbridge("fly", "--scenario", toml, "--processes", "1", "--log", log)
    assert proc.returncode == 0, proc.stderr
    return log, re.search(r"trace hash (\w+)", proc.stdout).group(1)


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("imu_raw")
    (on, hash_on), (off, hash_off) = _fly(d, True), _fly(d, False)
    assert hash_on == hash_off      # every record the FC got, and every PWM it sent
    return on, off


def test_the_raw_channel_is_there_only_when_asked_and_at_the_chips_rate(logs):
    on, off = (read_log(p) for p in logs)
    assert RAW_IMU_CHANNEL not in off.channels
    rows = on.channels[RAW_IMU_CHANNEL]
    assert on.metadata["config"][RATE_KEY] == 8000.0
    assert np.all(np.diff(rows["sim_ns"]) == 125_000)
    assert len(rows) == 8 * len(on.channels["/imu"])
    assert check_log(on) == []


def test_the_fcs_imu_is_identical_with_raw_logging_on_and_off(logs):
    """Every field the FC read (the wall-clock stamp of the read aside)."""
    on, off = (read_log(p).channels["/imu"] for p in logs)
    fields = [f for f in on.dtype.names if f != "wall_ns"]
    assert len(on) == len(off) == 12000
    for f in fields:
        assert on[f].tobytes() == off[f].tobytes(), f


@pytest.fixture(scope="module")
def gyro_spectrum(logs):
    """`analyze --spectrum --json` of the raw log's hover: (summary, FC block, chip block)."""
    proc = _silbridge("analyze", logs[0], "--spectrum", "--json", "--sensor", "gyro",
                      "--spectrum-window", *HOVER)
    assert proc.returncode == 0, proc.stderr
    s = json.loads(proc.stdout)["spectrum"]
    fc, chip = s["channels"]
    return s, fc, chip


def test_analyze_spectrum_reads_the_raw_channel_and_finds_the_rotor_lines(gyro_spectrum):
    s, fc, chip = gyro_spectrum
    assert (fc["channel"], chip["channel"]) == ("/imu", RAW_IMU_CHANNEL)
    assert chip["rate_hz"] == pytest.approx(8000.0)
    f_rot = s["rotor"]["median_hz"]
    found = {p["harmonic"]: p["freq_hz"] for axis in chip["axes"].values()
             for p in axis["peaks"] if p["harmonic"]}
    for k in (1, 2):
        assert found[k] == pytest.approx(k * f_rot, rel=0.01), (k, found, f_rot)


def test_a_line_above_the_fc_nyquist_is_true_in_the_raw_block_and_an_alias_at_fc_rate(
        logs, gyro_spectrum):
    s, fc, chip = gyro_spectrum
    line = 15 * s["rotor"]["median_hz"]
    alias = 1000.0 - line % 1000.0 if line % 1000.0 > 500.0 else line % 1000.0
    true_peaks = [p for p in chip["axes"]["gyro_x"]["peaks"] if p["freq_hz"] > 500.0]
    assert true_peaks and true_peaks[0]["freq_hz"] == pytest.approx(line, rel=0.01)
    folded = [p for p in fc["axes"]["gyro_x"]["peaks"] if p["alias_of_hz"]]
    assert folded and folded[0]["freq_hz"] == pytest.approx(alias, rel=0.01)
    assert folded[0]["alias_of_hz"] == pytest.approx(line, rel=0.01)
    assert folded[0]["amp"] == pytest.approx(true_peaks[0]["amp"], rel=0.1)
    text = _silbridge("analyze", logs[0], "--spectrum", "--sensor", "gyro",
                      "--spectrum-window", *HOVER).stdout
    assert f"(alias of {folded[0]['alias_of_hz']:.1f})" in text


@pytest.mark.parametrize("f, folded", [(1300.0, 300.0), (1700.0, 300.0), (300.0, 300.0),
                                       (2214.7, 214.7), (500.0, 500.0)])
def test_fold(f, folded):
    assert fold_hz(f, 1000.0) == pytest.approx(folded)
