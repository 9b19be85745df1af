"""The FFT's STATUSTEXTs (fc_sil/fft_notice.py, fc_fft_calibration), worded as ArduCopter 4.6.

The real ArduCopter 4.6.0 SITL with FFT_ENABLE=1 and its FFT defaults (1 kHz gyro, window 32,
overlap 0.5) sends "FFT: calibrated 1.0KHz/15.6Hz/187.5Hz" once its pre-arm checks reach the
FFT (measured 2026-11-28 from its dataflash MSG log, `--model quad`); ours, with the same
settings, must send the same text once the noise reference is learned, and only once.
"""

import pytest

from fft_block import tones
from vehicle_harness import fly_scripted

from silbridge.fc_sil.fft_notice import calibrated_text, motor_noise_text
from silbridge.fc_sil.flight_core import FlightCore

FS = 1000.0
ARDUCOPTER_4_6_DEFAULTS_TEXT = "FFT: calibrated 1.0KHz/15.6Hz/187.5Hz"


def _core(**params):
    core = FlightCore()
    core.set_param("FFT_ENABLE", 1)
    for name, value in params.items():
        core.set_param(name, value)
    return core


def _still(core, seconds, t0_ms=0):
    for i, g in enumerate(tones(FS, seconds, [], noise=0.002)):
        core.step_imu((t0_ms + i + 1) * 1_000_000, (0.0, 0.0, -9.80665), g)
    return t0_ms + int(seconds * FS)


def test_figures_and_text_match_arducopter_with_its_defaults():
    core = _core()
    assert core.fft_calibration() is None          # still learning the noise reference
    _still(core, 1.0)
    assert core.fft_calibration() == pytest.approx((1.0, 15.625, 187.5))
    assert calibrated_text(*core.fft_calibration()) == ARDUCOPTER_4_6_DEFAULTS_TEXT


def test_frame_time_is_whole_ms_as_arducopter():
    """3000 / whole ms per frame: 128-sample frames at 1 kHz are 128 ms -> 23.4 Hz."""
    core = _core(FFT_WINDOW_SIZE=256)
    _still(core, 2.0)
    assert calibrated_text(*core.fft_calibration()) == "FFT: calibrated 1.0KHz/2.0Hz/23.4Hz"


def test_the_vehicle_sends_it_once_while_disarmed():
    """The real vehicle on S1's physics, 3 s on the ground: the text once, as INFO."""
    flight, _res = fly_scripted(lambda f: None, duration_s=3.0, params={"FFT_ENABLE": 1})
    texts = [(sev, text) for _t, sev, text in flight.v.messages if text.startswith("FFT")]
    assert texts == [(6, ARDUCOPTER_4_6_DEFAULTS_TEXT)]      # MAV_SEVERITY_INFO


def test_motor_noise_text_is_arducopters():
    """"Noise %.fdB on motor %u at %.fHz" (AP_Vehicle::check_motor_noise)."""
    assert motor_noise_text(2, 45.6, 81.4) == "Noise 46dB on motor 2 at 81Hz"
