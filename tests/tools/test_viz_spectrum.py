"""The viewable vibration channel /viz/vibration (tools/logs/viz_spectrum.py) of a real flight.

A short lockstep flight with the rotor vibration raised (one process, 14 s of sim time): the
channel holds one message per 0.1 s of sim time, decodes with the mcap ROS 2 reader, and in
hover its largest gyro x peak sits at the logged rotor frequency (1/rev) and gyro z's at twice
it (blade pass), within the 4 Hz bins of its 0.25 s window; its band RMS agrees with
`analyze --spectrum`'s over the same stretch.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from silbridge.tools.logs.log_reader import read_log
from silbridge.tools.logs.spectrum_log import window_of
from silbridge.tools.logs.spectrum_summary import vibration_summary
from silbridge.tools.logs.viz_spectrum import VIBRATION_CHANNEL, WINDOW_S

mcap_ros2 = pytest.importorskip("mcap_ros2.decoder")

SCENARIO = """\
name = "VIB"
description = "hover at 3 m with the rotor vibration raised (Foxglove channel test)"
seed = 2
duration_s = 14.0
takeoff_alt_m = 3.0
[imu]
vib_accel = 6.0
vib_gyro = 0.05
"""


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    d = tmp_path_factory.mktemp("vizvib")
    (d / "vib.toml").write_text(SCENARIO)
    log = d / "vib.mcap"
    proc = subprocess.run([sys.executable, "-m", "silbridge.tools", "fly", "--scenario",
                           str(d / "vib.toml"), "--processes", "1", "--log", str(log)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    from mcap.reader import make_reader
    with open(log, "rb") as f:
        msgs = [(m.log_time, dec) for _s, _c, m, dec in make_reader(
            f, decoder_factories=[mcap_ros2.DecoderFactory()]).iter_decoded_messages(
                topics=[VIBRATION_CHANNEL])]
    return read_log(log), msgs


def test_ten_messages_per_second_of_sim_time(flight):
    log, msgs = flight
    t = np.array([ns for ns, _ in msgs])
    assert np.all(np.diff(t) == 100_000_000)
    # The first once a whole window of samples is in, the last at the end of the run.
    assert t[0] == pytest.approx(WINDOW_S * 1e9, abs=1e8)
    assert t[-1] == pytest.approx(log.duration_s() * 1e9, abs=1e8)


def test_hover_peaks_sit_at_the_rotor_harmonics(flight):
    log, msgs = flight
    rotor = log.channels["/rotor"]
    hover = [(ns, m) for ns, m in msgs if ns >= 10e9]
    assert len(hover) >= 35
    rt = rotor["sim_ns"]
    for ns, m in hover:
        f_rot = float(np.median(rotor["omega_rad_s"][np.searchsorted(rt, ns) - 1])) / (2 * np.pi)
        assert abs(m.gyro_x_peak_hz - f_rot) <= 1.0 / WINDOW_S, (ns, m.gyro_x_peak_hz, f_rot)
        assert abs(m.gyro_z_peak_hz - 2 * f_rot) <= 1.0 / WINDOW_S
        assert abs(m.accel_z_peak_hz - 2 * f_rot) <= 1.0 / WINDOW_S
    # The band RMS agrees with the analysis' Welch estimate over the same stretch.
    s = vibration_summary(log, window_of(log, (10.0, 14.0), (10.0, 14.0)), 1.0,
                          ["gyro", "accel"], 1)
    axes = s["channels"][0]["axes"]
    for field, axis in (("gyro_x_rms_rad_s", "gyro_x"), ("accel_z_rms_m_s2", "accel_z")):
        mean_sq = np.mean([getattr(m, field) ** 2 for _ns, m in hover])
        assert np.sqrt(mean_sq) == pytest.approx(axes[axis]["band_rms"], rel=0.1), field
