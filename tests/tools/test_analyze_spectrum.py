"""`silbridge analyze LOG --spectrum` on a real flight with known vibration.

One short lockstep flight (JSBSim + our FC, one process, 16 s of sim time, about a second of
wall time) with the sensor model's rotor-synchronous vibration raised: 1/rev on gyro x, y
and accel x, y; 2/rev (the blade pass of a two-blade prop) on gyro z and accel z
(bridge/imu.py). The spectrum's largest peaks must sit at 1x and 2x the logged rotor
frequency (/rotor) within the frequency resolution, and --track must follow them through
the take-off's throttle changes. A log without rotor speed says so; bad input is refused
in one line.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from silbridge.tools.logs.log_reader import read_log
from silbridge.tools.logs.log_synth import synthetic_run, write_run
from silbridge.tools.logs.mcap_log import LogWriter

SCENARIO = """\
name = "VIB"
description = "hover at 3 m with the rotor vibration raised (spectrum test)"
seed = 1
duration_s = 16.0
takeoff_alt_m = 3.0
[windows]
warmup_s = 1.0
transient_end_s = 2.0
[imu]
vib_accel = 6.0
vib_gyro = 0.05
"""
HOVER = ("10", "16")        # steady hover: the rotor speed holds within 0.1 %
TAKEOFF = ("5.2", "16")     # arming at 5 s, spool-up, climb and settling: 75-95 Hz


def _silbridge(*args, timeout=120):
    return subprocess.run([sys.executable, "-m", "silbridge.tools", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout)


def _spectrum_json(log, *args) -> dict:
    proc = _silbridge("analyze", log, "--spectrum", "--json", *args)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    d = tmp_path_factory.mktemp("vib")
    (d / "vib.toml").write_text(SCENARIO)
    log = d / "vib.mcap"
    proc = _silbridge("fly", "--scenario", d / "vib.toml", "--processes", "1", "--log", log)
    assert proc.returncode == 0, proc.stderr
    return log


def test_peaks_sit_at_the_rotor_harmonics_within_the_resolution(flight):
    out = _spectrum_json(flight, "--spectrum-window", *HOVER)
    s = out["spectrum"]
    rotor = s["rotor"]["median_hz"]
    rotor_rows = read_log(flight).channels["/rotor"]
    t = rotor_rows["sim_ns"] * 1e-9
    hover = rotor_rows["omega_rad_s"][(t >= 10) & (t <= 16)] / (2 * np.pi)
    assert rotor == pytest.approx(float(np.median(hover)))
    assert 50 < rotor < 120                  # a 10-inch prop at hover
    (imu,) = s["channels"]
    res = imu["resolution_hz"]
    assert imu["channel"] == "/imu" and imu["rate_hz"] == pytest.approx(1000.0)
    assert res == pytest.approx(1.0)         # 1 s segments
    for axis, k in (("gyro_x", 1), ("gyro_y", 1), ("accel_y", 1),
                    ("gyro_z", 2), ("accel_z", 2)):     # 1/rev in the rotor plane, 2/rev on z
        top = imu["axes"][axis]["peaks"][0]
        assert abs(top["freq_hz"] - k * rotor) <= res, (axis, top, rotor)
        assert top["harmonic"] == k and top["order"] == pytest.approx(k, abs=res / rotor)


def test_track_follows_the_harmonics_through_the_throttle_changes(flight):
    s = _spectrum_json(flight, "--spectrum-window", *TAKEOFF, "--track")["spectrum"]
    (imu,) = s["channels"]
    lo, hi = imu["track"]["rotor_hz_range"]
    assert hi / lo > 1.15                    # the window swept the rotor speed
    for axis, k in (("gyro_x", 1), ("gyro_z", 2), ("accel_y", 1), ("accel_z", 2)):
        row = imu["axes"][axis]["track"][k - 1]
        assert row["k"] == k and row["found"] == row["segments"] > 40, (axis, row)
        assert row["max_dev_pct"] < 1.0, (axis, row)      # the 1 %


def test_json_structure_and_options(flight):
    out = _spectrum_json(flight, "--spectrum-window", *HOVER, "--sensor", "gyro",
                         "--segment-s", "0.5", "--peaks", "2")
    assert out["ok"] is True and out["problems"] == []
    s = out["spectrum"]
    assert s["window_s"] == [10.0, 16.0] and s["window_note"] == ""
    assert (s["segment_s"], s["overlap"], s["window_fn"]) == (0.5, 0.5, "hann")
    assert len(s["rotor"]["per_motor_hz"]) == 4 and s["rotor_note"] == ""
    assert s["rotor"]["harmonics_hz"]["2"] == pytest.approx(2 * s["rotor"]["median_hz"])
    (imu,) = s["channels"]
    assert imu["resolution_hz"] == pytest.approx(2.0) and imu["segment_n"] == 500
    assert imu["segments"] == 23             # 6 s of 0.5 s segments, half overlapping
    assert sorted(imu["axes"]) == ["gyro_x", "gyro_y", "gyro_z"]
    for v in imu["axes"].values():
        assert v["unit"] == "rad/s" and v["band_rms"] > 0 and 1 <= len(v["peaks"]) <= 2
        assert set(v["peaks"][0]) == {"freq_hz", "amp", "harmonic", "order"}
    # The table says the same.
    proc = _silbridge("analyze", flight, "--spectrum", "--spectrum-window", *HOVER)
    assert proc.returncode == 0, proc.stderr
    assert "resolution 1 Hz" in proc.stdout and "rotor: median" in proc.stdout
    assert "(1x)" in proc.stdout and "(2x)" in proc.stdout


def test_a_log_without_rotor_speed_says_so(tmp_path):
    run = synthetic_run(6.0)
    path = tmp_path / "no_rotor.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    s = _spectrum_json(path, "--spectrum-window", 1, 6)["spectrum"]
    assert s["rotor"] is None and s["rotor_note"] == "no rotor speed in this log"
    assert all(p["harmonic"] is None for v in s["channels"][0]["axes"].values()
               for p in v["peaks"])
    proc = _silbridge("analyze", path, "--spectrum", "--spectrum-window", 1, 6)
    assert "no rotor speed in this log" in proc.stdout
    proc = _silbridge("analyze", path, "--spectrum", "--spectrum-window", 1, 6, "--track")
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
    assert "no rotor speed in this log" in proc.stderr


@pytest.mark.parametrize("args, says", [
    (("--spectrum-window", 20, 30), "lies outside the log"),
    (("--spectrum-window", 12, 11), "is empty"),
    (("--spectrum-window", 15, 16, "--segment-s", 2), "fewer than one 2 s segment"),
    (("--peaks", 0), "--peaks 0"),
])
def test_bad_input_is_refused_in_one_line(flight, args, says):
    proc = _silbridge("analyze", flight, "--spectrum", *args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0], proc.stderr


def test_a_log_without_imu_is_refused_in_one_line(tmp_path):
    run = synthetic_run(4.0)
    del run.channels["/imu"]
    path = tmp_path / "no_imu.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
    proc = _silbridge("analyze", path, "--spectrum", "--force")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "has no IMU channel" in lines[0], proc.stderr


def test_the_chips_raw_channel_gets_its_own_spectrum(tmp_path):
    """A log with the chip's raw samples (/imu_raw, 8 kHz) beside the FC's /imu (1 kHz): a
    1.3 kHz vibration shows at 1.3 kHz in the raw spectrum, and where the 1 kHz samples
    alias it (300 Hz) in the FC's. (Synthetic samples: the channels' plumbing, not the chip.)"""
    run = synthetic_run(4.0)
    imu = run.channels["/imu"]
    t_fc = imu["sim_ns"] * 1e-9
    imu["gyro_frd_rad_s"][:, 2] += 0.05 * np.sin(2 * np.pi * 1300.0 * t_fc)
    raw_ns = np.arange(1, 4 * 8000 + 1, dtype=np.int64) * 125_000
    raw = np.zeros(len(raw_ns), dtype=[("sim_ns", "<i8"), ("gyro_frd_rad_s", "<f4", (3,)),
                                       ("accel_frd_m_s2", "<f4", (3,))])
    raw["sim_ns"] = raw_ns
    raw["gyro_frd_rad_s"][:, 2] = 0.05 * np.sin(2 * np.pi * 1300.0 * raw_ns * 1e-9)
    raw["accel_frd_m_s2"][:, 2] = -9.81
    path = tmp_path / "raw.mcap"
    with LogWriter(path, metadata=run.metadata) as w:
        write_run(run, w)
        w.write("/imu_raw", raw)
    s = _spectrum_json(path, "--spectrum-window", 0, 4, "--sensor", "gyro")["spectrum"]
    fc, chip = s["channels"]
    assert (fc["channel"], chip["channel"]) == ("/imu", "/imu_raw")
    assert chip["rate_hz"] == pytest.approx(8000.0) and fc["rate_hz"] == pytest.approx(1000.0)
    assert chip["axes"]["gyro_z"]["peaks"][0]["freq_hz"] == pytest.approx(1300.0, abs=0.1)
    assert fc["axes"]["gyro_z"]["peaks"][0]["freq_hz"] == pytest.approx(300.0, abs=0.1)
    assert chip["axes"]["gyro_z"]["peaks"][0]["amp"] == pytest.approx(0.05, rel=0.02)
