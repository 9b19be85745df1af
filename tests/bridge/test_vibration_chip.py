"""The IMU chip's pipeline stands alone in C (bridge/src/imu_chip.c, built here with gcc and
no Python headers): a 1.3 kHz vibration sampled at the chip's data rate and read by the FC
at 1 kHz aliases to 300 Hz with the anti-alias filter off, and is attenuated by the
declared filter's gain with it on; the declared gain is scipy's Butterworth."""

import ctypes
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from silbridge.bridge.vibration_consts import aaf_gain

ROOT = Path(__file__).resolve().parents[2]
FC_HZ = 1000
VIB_HZ = 1300.0


class ChipConsts(ctypes.Structure):
    _fields_ = [("odr_hz", ctypes.c_double), ("aaf_hz", ctypes.c_double),
                ("aaf_order", ctypes.c_double)]


class Chip(ctypes.Structure):
    _fields_ = [("on", ctypes.c_int), ("odr_hz", ctypes.c_double), ("coef", ctypes.c_double * 5),
                ("s1", ctypes.c_double * 6), ("s2", ctypes.c_double * 6),
                ("ramp_n", ctypes.c_int), ("ramp", ctypes.c_double * 12)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    so = tmp_path_factory.mktemp("chip") / "libchip.so"
    subprocess.run([cc, "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-ffp-contract=off",
                    "-shared", "-fPIC", str(ROOT / "bridge" / "src" / "imu_chip.c"), "-lm",
                    "-o", str(so)], check=True, capture_output=True, text=True)
    return ctypes.CDLL(str(so))


def read_at_fc_rate(lib, odr_hz, aaf_hz, order, seconds=2.0):
    """A unit 1.3 kHz sine on every channel, through the chip; every n-th output."""
    chip = Chip()
    lib.sb_chip_init(ctypes.byref(chip), ctypes.byref(ChipConsts(odr_hz, aaf_hz, order)))
    n = odr_hz // FC_HZ
    x6, y6 = (ctypes.c_double * 6)(), (ctypes.c_double * 6)()
    out = []
    for i in range(1, int(seconds * odr_hz) + 1):
        v = math.sin(2 * math.pi * VIB_HZ * i / odr_hz)
        for c in range(6):
            x6[c] = v
        lib.sb_chip_sample(ctypes.byref(chip), x6, y6)
        if i % n == 0:
            out.append(y6[4])
    return np.array(out[len(out) // 4:])          # past the filter's start


def amplitude_at(x, f_hz):
    t = np.arange(len(x)) / FC_HZ
    a = np.column_stack([np.cos(2 * np.pi * f_hz * t), np.sin(2 * np.pi * f_hz * t),
                         np.ones_like(t)])
    c, s, _ = np.linalg.lstsq(a, x, rcond=None)[0]
    return math.hypot(c, s)


def peak_hz(x):
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    return np.fft.rfftfreq(len(x), 1.0 / FC_HZ)[np.argmax(spec)]


@pytest.mark.parametrize("odr_hz", [32000, 8000, 1000])
def test_aaf_off_a_1300_hz_vibration_aliases_to_300_hz_at_full_amplitude(lib, odr_hz):
    y = read_at_fc_rate(lib, odr_hz, 585.0, 0)
    assert abs(peak_hz(y) - 300.0) <= 1.0
    assert amplitude_at(y, 300.0) == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("odr_hz,aaf_hz", [(32000, 585.0), (32000, 258.0), (8000, 585.0)])
def test_aaf_on_attenuates_the_alias_by_the_declared_gain(lib, odr_hz, aaf_hz):
    y = read_at_fc_rate(lib, odr_hz, aaf_hz, 2)
    declared = aaf_gain(VIB_HZ, aaf_hz, odr_hz)
    assert declared < 0.25                          # -12 dB or better: it does something
    assert amplitude_at(y, 300.0) == pytest.approx(declared, rel=1e-3)


def test_a_physics_step_of_ramp_samples_in_one_map_is_the_filter_run_sample_by_sample(lib):
    """The stage runs the rigid-body motion (linear over a step) through the AAF with
    sb_chip_ramp: the same state and output as n sb_chip_sample calls."""
    n = 32
    ramp, each = Chip(), Chip()
    for chip in (ramp, each):
        lib.sb_chip_init(ctypes.byref(chip), ctypes.byref(ChipConsts(32000, 585.0, 2)))
    lib.sb_chip_ramp_init(ctypes.byref(ramp), n)
    rng = np.random.default_rng(1)
    prev = rng.standard_normal(6)
    for _ in range(50):
        cur = prev + rng.standard_normal(6)
        y_ramp, y_each = (ctypes.c_double * 6)(), (ctypes.c_double * 6)()
        lib.sb_chip_ramp(ctypes.byref(ramp), (ctypes.c_double * 6)(*prev),
                         (ctypes.c_double * 6)(*cur), y_ramp)
        for j in range(1, n + 1):
            x = (ctypes.c_double * 6)(*(prev + j / n * (cur - prev)))
            lib.sb_chip_sample(ctypes.byref(each), x, y_each)
        assert np.allclose(list(y_ramp), list(y_each), rtol=0, atol=1e-11)
        assert np.allclose(list(ramp.s1), list(each.s1), rtol=0, atol=1e-11)
        prev = cur


@pytest.mark.parametrize("odr_hz,aaf_hz,f_hz", [(32000, 585.0, 1300.0), (8000, 585.0, 1300.0),
                                                (1000, 258.0, 1300.0), (32000, 2029.0, 150.0)])
def test_the_gain_the_stage_applies_to_a_vibration_line_is_what_the_filter_does(
        lib, odr_hz, aaf_hz, f_hz):
    """The stage reads each vibration line through sb_chip_gain (the AAF's response at the
    line's frequency, aliases included); it must be the running filter's amplitude."""
    chip = Chip()
    lib.sb_chip_init(ctypes.byref(chip), ctypes.byref(ChipConsts(odr_hz, aaf_hz, 2)))
    re, im = ctypes.c_double(), ctypes.c_double()
    lib.sb_chip_gain(ctypes.byref(chip), ctypes.c_double(2 * math.pi * f_hz),
                     ctypes.byref(re), ctypes.byref(im))
    assert math.hypot(re.value, im.value) == pytest.approx(aaf_gain(f_hz, aaf_hz, odr_hz),
                                                           rel=1e-9)


def test_declared_gain_is_a_2nd_order_butterworth_with_its_3db_point_at_aaf_hz():
    signal = pytest.importorskip("scipy.signal")
    b, a = signal.butter(2, 585.0, fs=32000.0)
    for f in (100.0, 585.0, 1300.0, 5000.0):
        _, h = signal.freqz(b, a, worN=[f], fs=32000.0)
        assert aaf_gain(f, 585.0, 32000.0) == pytest.approx(abs(h[0]), rel=1e-9)
    assert aaf_gain(585.0, 585.0, 32000.0) == pytest.approx(math.sqrt(0.5), rel=1e-9)
