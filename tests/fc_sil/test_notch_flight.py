"""The harmonic notch in flight: V2 (one bent prop, hard-mounted IMU) with ESC telemetry,
flown by the real closed loop (`silbridge fly`, lockstep, one process), the notch off and on.

What is measured is the FC's own filtered gyro (/fc/status rate_frd_rad_s, the rate loop's
input, logged at the 400 Hz PWM tick: the 81 Hz rotor line and its 2x sit below its Nyquist)
and the PWM, against the same flight without the notch.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from silbridge.tools.logs.log_reader import read_log

ROOT = Path(__file__).resolve().parents[2]
WINDOW_S = (12.0, 22.0)        # hover, after the climb to 10 m has settled


def _scenario(tmp_path: Path, extra: str = "") -> Path:
    text = (ROOT / "bridge" / "scenarios" / "V2.toml").read_text()
    path = tmp_path / "V2_notch.toml"
    path.write_text(text.replace('name = "V2"', 'name = "V2_notch"')
                    + "\n[esc]\ntelemetry_hz = 50.0\n" + extra)
    return path


def _fly(scenario: Path, log: Path, params: dict) -> None:
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--scenario", str(scenario),
           "--duration", "22", "--processes", "1", "--no-mavlink", "--log", str(log)]
    for k, v in params.items():
        cmd += ["--param", f"{k}={v}"]
    subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=600)


def _window(log, channel):
    rows = log.channels[channel]
    t = rows["sim_ns"] * 1e-9
    return rows[(t >= WINDOW_S[0]) & (t < WINDOW_S[1])]


def _line_amp(log, hz: float) -> np.ndarray:
    """The FC's filtered gyro at hz, per axis: the amplitude of the sinusoid holding the power
    within +-2 Hz of it [rad/s] (Welch, 1 s Hann segments; docs/howto/harmonic-notch.md)."""
    g = _window(log, "/fc/status")["rate_frd_rad_s"].astype(float)
    f, p = signal.welch(g, fs=400.0, nperseg=400, axis=0, scaling="density")
    k = int(np.argmin(abs(f - hz)))
    return np.sqrt(2.0 * p[k - 2:k + 3].sum(axis=0) * (f[1] - f[0]))


def _pwm(log) -> np.ndarray:
    rows = _window(log, "/pwm")
    name = next(n for n in rows.dtype.names if "pwm" in n)
    return rows[name].astype(float)


def _hover(log) -> tuple[float, float]:
    """(rotor frequency [Hz], mixer throttle as a fraction of the PWM range) at hover: what
    a user reads off a first flight to set FREQ and REF (docs/howto/harmonic-notch.md)."""
    rotor_hz = float(np.median(_window(log, "/rotor")["omega_rad_s"]) / (2 * np.pi))
    thr = (_window(log, "/fc/status")["throttle_us"] - 1000.0) / 1000.0   # MOT_PWM_MIN/MAX
    return rotor_hz, float(np.median(thr))


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("notch_flights")
    scen = _scenario(tmp)
    _fly(scen, tmp / "off.mcap", {})
    logs = {"off": read_log(tmp / "off.mcap")}
    rotor_hz, hover_thr = _hover(logs["off"])
    runs = {
        # ESC telemetry, one centre per motor, 1x and 2x (INS_HNTCH_HMNCS default 3)
        "esc": dict(INS_HNTCH_ENABLE=1, INS_HNTCH_MODE=3, INS_HNTCH_REF=1, INS_HNTCH_FREQ=60,
                    INS_HNTCH_BW=30, INS_HNTCH_OPTS=2),
        # throttle: the rotor frequency at the hover throttle
        "thr": dict(INS_HNTCH_ENABLE=1, INS_HNTCH_MODE=1, INS_HNTCH_REF=round(hover_thr, 3),
                    INS_HNTCH_FREQ=round(rotor_hz, 1), INS_HNTCH_BW=40, INS_HNTCH_FM_RAT=0.7),
    }
    for name, params in runs.items():
        path = tmp / f"{name}.mcap"
        _fly(scen, path, params)
        logs[name] = read_log(path)
    return logs


def test_rotor_line_is_attenuated_20_db_by_each_tracking_mode(flights):
    rotor_hz, _ = _hover(flights["off"])
    off = _line_amp(flights["off"], rotor_hz)
    assert off.max() > 1e-3                                  # the line is there to remove
    for mode in ("esc", "thr"):
        on = _line_amp(flights[mode], rotor_hz)
        gain_db = 20 * np.log10(on.max() / off.max())
        assert gain_db <= -20.0, (mode, gain_db)


def test_notch_lowers_the_pwm_noise(flights):
    off = _pwm(flights["off"]).std(axis=0).mean()
    for mode in ("esc", "thr"):
        assert _pwm(flights[mode]).std(axis=0).mean() < 0.8 * off, mode


def test_retune_in_flight_causes_no_pwm_jump(flights, tmp_path):
    """A fixed notch 5 Hz below the rotor line retuned to 5 Hz above it at 15 s (both cover
    the line; V2: 76 -> 86 Hz): the PWM's tick-to-tick change in the second after it stays
    within the noise of the steady flight, before the retune and after it has settled."""
    rotor_hz, _ = _hover(flights["off"])
    scen = _scenario(tmp_path, f'\n[[fc_param]]\nname = "INS_HNTCH_FREQ"\n'
                               f'value = {rotor_hz + 5.0:.1f}\nat_s = 15.0\n')
    log_path = tmp_path / "retune.mcap"
    _fly(scen, log_path, dict(INS_HNTCH_ENABLE=1, INS_HNTCH_MODE=0,
                              INS_HNTCH_FREQ=round(rotor_hz - 5.0, 1), INS_HNTCH_BW=40))
    log = read_log(log_path)
    rows = log.channels["/pwm"]
    t = rows["sim_ns"] * 1e-9
    name = next(n for n in rows.dtype.names if "pwm" in n)
    step = np.abs(np.diff(rows[name].astype(float), axis=0)).max(axis=1)
    before = step[(t[1:] >= 11.0) & (t[1:] < 15.0)].max()
    retune = step[(t[1:] >= 15.0) & (t[1:] < 16.0)].max()
    settled = step[(t[1:] >= 17.0) & (t[1:] < 22.0)].max()
    assert retune <= max(before, settled)
