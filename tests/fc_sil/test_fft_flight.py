"""The in-flight FFT in a real flight (issue 27's test): V2 (motor 1's bent prop, vibration
on, hard-mounted IMU) flown by `silbridge fly` with FFT_ENABLE=1. Its FTN1 rows (the log's
/fc/ftn1, 10 Hz as ArduCopter writes them) track the rotor frequency the bridge logs (/rotor,
each motor's speed) within 3 % through the settled hover, and FTN2 carries the tracked
peaks.

FFT_WINDOW_SIZE 256 (3.9 Hz bins at 1 kHz) as a tuner sets it for resolution; ArduCopter's
default 32 has 31 Hz bins. FFT_MINHZ 50 keeps the hover's ~81 Hz rotor off the search's edge.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np

from silbridge.tools.logs.ftn_log import FTN1_CHANNEL, FTN1_DTYPE, FTN2_CHANNEL, FTN2_DTYPE
from silbridge.tools.logs.mcap_log import read_log

ROOT = Path(__file__).resolve().parents[2]
# V2's settled hover (bridge/scenarios/V2.toml [windows] transient_end_s): before it the
# climb's end moves the rotors by ~4 Hz/s and a 256-sample window lags by up to ~3 %.
HOVER_FROM_S = 30.0
DURATION_S = 40


def _fly_v2(log: Path) -> None:
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--scenario",
           str(ROOT / "bridge/scenarios/V2.toml"), "--duration", str(DURATION_S),
           "--processes", "1", "--no-mavlink", "--viz-hz", "0", "--log", str(log),
           "--param", "FFT_ENABLE=1", "--param", "FFT_WINDOW_SIZE=256",
           "--param", "FFT_MINHZ=50"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]


def test_v2_fft_tracks_the_rotor_within_3_percent(tmp_path):
    log = tmp_path / "v2_fft.mcap"
    _fly_v2(log)
    ch = read_log(str(log)).channels
    ftn1, ftn2, rotor = ch[FTN1_CHANNEL], ch[FTN2_CHANNEL], ch["/rotor"]
    assert ftn1.dtype == FTN1_DTYPE and ftn2.dtype == FTN2_DTYPE
    # 10 Hz of IMU time, as ArduCopter's ten_hz_logging_loop
    assert np.all(np.diff(ftn1["sim_ns"][1:]) == 100_000_000)   # after the first sample
    assert set(ftn2["id"].tolist()) == {0, 1, 2}   # INS_HNTCH_HMNCS default 3: two harmonics

    hover = ftn1[ftn1["sim_ns"] >= HOVER_FROM_S * 1e9]
    assert len(hover) >= 10 * (DURATION_S - HOVER_FROM_S) - 1
    rotor_hz = rotor["rpm"].mean(axis=1) / 60.0
    at = np.searchsorted(rotor["sim_ns"], hover["sim_ns"]).clip(0, len(rotor) - 1)
    err = np.abs(hover["pk_avg_hz"] - rotor_hz[at]) / rotor_hz[at]
    worst = err.argmax()
    assert err[worst] <= 0.03, (err[worst], hover["pk_avg_hz"][worst], rotor_hz[at][worst])
    assert (hover["health"] >= 1).all()
    assert (hover["snr_db"][:, :2] > 25.0).all()    # roll and pitch above FFT_SNR_REF


def test_hover_learning_is_saved_on_disarm():
    """The vehicle hovers V2 in GUIDED with FFT_ENABLE=1 and FFT_FREQ_HOVER started far off
    (120 Hz): in the level hover it learns toward the rotor line (10 s time constant,
    AP_GyroFFT::update_freq_hover) and the learned values become the parameters on disarm."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from vehicle_harness import fly_scripted

    from silbridge.mavlink.gcs.vehicle_api import CopterMode

    st = {}

    def script(f):
        v, t = f.v, f.t_s
        if t > 3 and "up" not in st:
            st["up"] = True
            v.set_mode(CopterMode.GUIDED)
            v.arm(False)
            v.takeoff(8.0)
        if t > 35 and "down" not in st:
            st["down"] = True
            st["learning"] = v.core.get_param("FFT_FREQ_HOVER")   # not saved while armed
            v.disarm(True)

    params = {"FFT_ENABLE": 1, "FFT_WINDOW_SIZE": 256, "FFT_MINHZ": 50, "FFT_FREQ_HOVER": 120}
    f, _ = fly_scripted(script, duration_s=36, scenario=str(ROOT / "bridge/scenarios/V2.toml"),
                        params=params)
    core = f.v.core
    assert st["learning"] == 120.0
    learned = core.get_param("FFT_FREQ_HOVER")
    assert 79.0 < learned < 100.0, learned                # moved most of the way to ~81 Hz
    assert core.get_param("FFT_THR_REF") != 0.35          # the throttle reference learned too
