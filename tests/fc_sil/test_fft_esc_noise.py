"""FFT_OPTIONS bit 1 (fc_fft_esc.c): ArduCopter 4.6's motor-noise check, on synthetic gyro.

A 81 Hz line 50 dB above the learned noise floor stays in the (post-filter) gyro while the
ESCs report motors 1 and 2 at that frequency:
- both are named, not before 5 s of the check's clock, then at most once per 5 s;
- a motor at 0 Hz (no report) or at a frequency with no peak within one bin is not;
- nothing without bit 0 (the check reads the filtered gyro), disarmed, or with a notch
  that follows the FFT; nothing under 40 dB.
"""

import pytest

from fft_block import GyroFft, ffi, lib, tones

FS = 1000.0
LINE_HZ = 81.0
CHECK_S = 0.2                     # ArduCopter's 5 Hz check_motor_noise task


def _fft(options=3, amplitude=0.5):
    fft = GyroFft(FS, window_size=256, min_hz=40.0, max_hz=450.0, options=options)
    fft.feed(tones(FS, 1.0, [], noise=0.002, seed=7))          # still: the noise reference
    assert fft.f.needs_calibration == 0
    fft.feed(tones(FS, 2.0, [(LINE_HZ, amplitude, 0.0)], noise=0.002))
    return fft


def _checks(fft, motor_hz, n_checks, amplitude=0.5, armed=True, fft_notch=False):
    """Gyro for CHECK_S, then one check, n times: the check index and motors named."""
    hz = ffi.new("float[]", motor_hz)
    named = []
    for i in range(n_checks):
        fft.feed(tones(FS, CHECK_S, [(LINE_HZ, amplitude, 0.0)], noise=0.002, seed=i))
        warn = lib.fc_fft_esc_noise_check(fft.f, hz, len(motor_hz), armed, fft_notch, CHECK_S)
        if warn:
            named.append((i, [m for m in range(len(motor_hz)) if warn >> m & 1]))
    return named


def test_noise_at_a_motor_frequency_is_the_tracked_peaks_snr():
    fft = _fft()
    snr = lib.fc_fft_noise_at_hz(fft.f, LINE_HZ)
    assert snr > 40.0
    assert lib.fc_fft_noise_at_hz(fft.f, LINE_HZ + 0.9 * fft.f.bin_hz) == snr
    assert lib.fc_fft_noise_at_hz(fft.f, LINE_HZ + 1.5 * fft.f.bin_hz) == 0.0
    assert lib.fc_fft_noise_at_hz(fft.f, 120.0) == 0.0


def test_motors_at_the_line_are_named_after_5_s_then_every_5_s():
    fft = _fft()
    named = _checks(fft, [LINE_HZ, LINE_HZ - 1.0, 0.0, 120.0], 60)
    # the clock runs from init: the first round once more than 5 s have passed (26 checks)
    assert named == [(25, [0, 1]), (51, [0, 1])]
    assert fft.f.esc_noise.energy_db[0] > 40.0 and fft.f.esc_noise.energy_db[3] == 0.0


@pytest.mark.parametrize("options,armed,fft_notch", [(2, True, False), (3, False, False),
                                                      (3, True, True), (1, True, False)])
def test_off_unless_armed_post_filter_and_no_fft_notch(options, armed, fft_notch):
    fft = _fft(options=options)
    assert _checks(fft, [LINE_HZ], 40, armed=armed, fft_notch=fft_notch) == []


def test_a_line_under_40_db_is_not_named():
    fft = _fft(amplitude=0.05)                   # 20 dB lower: ~30 dB above the floor
    assert 20.0 < lib.fc_fft_noise_at_hz(fft.f, LINE_HZ) < 40.0
    assert _checks(fft, [LINE_HZ], 40, amplitude=0.05) == []
