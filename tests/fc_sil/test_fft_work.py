"""fc_fft spreads its work: no IMU step pays for a whole FFT.

Every fc_fft_step spends at most FC_FFT_STEP_UNITS units (a windowed sample, a butterfly,
a bin), the declared share; a frame therefore takes many steps, and the analysis still
keeps up with the FFT_WINDOW_OLAP schedule (every axis analysed once per hop).
"""

import math

import numpy as np
import pytest

from fft_block import GyroFft, lib, tones

FS = 1000.0


def _frame_units(n):
    """The least work of one frame: load, butterflies, power (scan and widths come on top)."""
    return n + (n // 2) * int(math.log2(n)) + n // 2 + 1


@pytest.mark.parametrize("n,olap", [(32, 0.5), (128, 0.5), (256, 0.5), (512, 0.5)])
def test_no_step_spends_more_than_its_share(n, olap):
    fft = GyroFft(FS, window_size=n, window_overlap=olap, min_hz=40.0, max_hz=450.0)
    rows = tones(FS, 4.0, [(90.0, 0.05, 0.0), (180.0, 0.1, 0.3)], noise=0.002)
    units = fft.feed(rows)
    share = lib.FC_FFT_STEP_UNITS
    assert units.max() <= share                      # the declared share, never more
    assert fft.f.max_units <= share
    # a frame is spread over at least this many IMU steps
    assert fft.f.frame_samples >= math.ceil(_frame_units(n) / share) - 1
    # and the schedule holds: each axis analysed about once per hop of samples
    hop = fft.f.hop
    expected = 3 * (len(rows) - n) / hop
    assert fft.f.frames_done >= 0.9 * expected, (fft.f.frames_done, expected)


def test_idle_steps_spend_nothing():
    """Between frames (window not yet refilled) a step returns at once."""
    fft = GyroFft(FS, window_size=256, window_overlap=0.0)
    units = fft.feed(np.zeros((200, 3)))              # fewer samples than one window
    assert units.max() == 0


def test_a_schedule_beyond_the_share_drops_frames_not_the_bound():
    """512 samples at 0.75 overlap needs more than the share per sample at 1 kHz: frames are
    dropped (the window jumps to the newest samples, as AP_GyroFFT::run_cycle does), the
    per-step bound holds and the peak is still found."""
    fft = GyroFft(FS, window_size=512, window_overlap=0.75, min_hz=40.0, max_hz=450.0)
    fft.feed(tones(FS, 3.0, [], noise=0.002, seed=3))   # the reference: 36 frames here
    assert fft.f.needs_calibration == 0
    units = fft.feed(tones(FS, 3.0, [(120.0, 0.08, 0.0)], noise=0.002))
    assert units.max() <= lib.FC_FFT_STEP_UNITS
    assert abs(fft.center_hz() - 120.0) < fft.f.bin_hz
