"""fc_filter.c: PT1, PT2, PT2x2, biquad low-pass and notch against scipy.signal.

Every filter is run through the real C code (fc_blocks.py, cffi bindings). Its
impulse response must equal scipy's for the design fc_filter.h documents, and
its gain and phase, measured from a steady sine, must match scipy.freqz.
"""

import numpy as np
import pytest
from scipy import signal

import fc_blocks as B

FS = 1000.0


def stage_gain(cutoff_hz, fs, n):
    """Per-stage k such that n discrete PT1 stages are -3 dB at the cutoff:
    solve k^2 / (1 - 2(1-k) cos w + (1-k)^2) = 2^(-1/n) (fc_filter.c)."""
    w = 2 * np.pi * cutoff_hz / fs
    g = 2 ** (-1 / n)
    # (1-g) u^2 - 2 (1 - g cos w) u + (1-g) = 0 with u = 1 - k; the root in (0, 1)
    roots = np.roots([1 - g, -2 * (1 - g * np.cos(w)), 1 - g])
    u = roots[(roots > 0) & (roots < 1)].real[0]
    return 1 - u


def ptn_ba(cutoff_hz, fs, n):
    """n identical PT1 stages, cutoff placed as fc_filter.h documents."""
    k = stage_gain(cutoff_hz, fs, n)
    b, a = np.array([1.0]), np.array([1.0])
    for _ in range(n):
        b = np.convolve(b, [k])
        a = np.convolve(a, [1, k - 1])
    return b, a


def reference(kind, cutoff, fs, bw=0.0):
    if kind == "pt1":
        return ptn_ba(cutoff, fs, 1)
    if kind == "pt2":
        return ptn_ba(cutoff, fs, 2)
    if kind == "pt2x2":
        return ptn_ba(cutoff, fs, 4)
    if kind == "lpf":
        return signal.butter(2, cutoff, fs=fs)
    if kind == "notch":
        return signal.iirnotch(cutoff, cutoff / bw, fs=fs)
    raise ValueError(kind)


def make(kind, cutoff, fs, bw=0.0):
    return {"pt1": lambda: B.PT1(cutoff, fs), "pt2": lambda: B.PT2(cutoff, fs),
            "pt2x2": lambda: B.PT2x2(cutoff, fs), "lpf": lambda: B.BiquadLowPass(cutoff, fs),
            "notch": lambda: B.Notch(cutoff, bw, fs)}[kind]()


CASES = [("pt1", 20.0, 0.0), ("pt2", 20.0, 0.0), ("pt2x2", 20.0, 0.0), ("lpf", 20.0, 0.0),
         ("lpf", 80.0, 0.0), ("notch", 80.0, 40.0), ("notch", 150.0, 20.0)]


@pytest.mark.parametrize("kind,cutoff,bw", CASES)
def test_impulse_response_matches_scipy_design(kind, cutoff, bw):
    f = make(kind, cutoff, FS, bw)
    x = np.zeros(2000)
    x[0] = 1.0
    h = f.apply(x)
    b, a = reference(kind, cutoff, FS, bw)
    np.testing.assert_allclose(h, signal.lfilter(b, a, x), atol=2e-6)


def steady_sine_response(f, freq_hz, fs, periods=60):
    """Gain and phase of the C filter from a sine, after the transient has died."""
    n_per = fs / freq_hz
    n = int(round(n_per * periods))
    t = np.arange(n) / fs
    y = f.apply(np.sin(2 * np.pi * freq_hz * t)).astype(np.float64)
    keep = slice(n // 2, n)   # second half: steady state
    basis = np.exp(-2j * np.pi * freq_hz * t[keep])
    c_out = 2 * np.mean(y[keep] * basis)
    c_in = 2 * np.mean(np.sin(2 * np.pi * freq_hz * t[keep]) * basis)
    h = c_out / c_in
    return abs(h), np.angle(h)


@pytest.mark.parametrize("kind,cutoff,bw", CASES)
def test_attenuation_and_phase_match_scipy_freqz(kind, cutoff, bw):
    b, a = reference(kind, cutoff, FS, bw)
    for freq in (5.0, cutoff, 2 * cutoff + 7.0, 300.0):
        if kind == "notch" and abs(freq - cutoff) < 1e-9:
            continue  # the null itself: gain ~0, phase undefined (checked below)
        f = make(kind, cutoff, FS, bw)
        gain, phase = steady_sine_response(f, freq, FS)
        _, h_ref = signal.freqz(b, a, worN=[freq], fs=FS)
        assert 20 * np.log10(gain) == pytest.approx(20 * np.log10(abs(h_ref[0])), abs=0.05)
        if gain > 1e-3:
            dphi = np.angle(np.exp(1j * (phase - np.angle(h_ref[0]))))
            assert abs(dphi) < 0.01


@pytest.mark.parametrize("kind", ["pt2", "pt2x2", "lpf"])
def test_cutoff_is_the_minus_3db_point(kind):
    # The cascade is -3 dB at the cutoff, also close to Nyquist.
    for cutoff in (20.0, 150.0):
        gain, _ = steady_sine_response(make(kind, cutoff, FS), cutoff, FS)
        assert 20 * np.log10(gain) == pytest.approx(-3.01, abs=0.02)


def test_notch_removes_its_centre_frequency():
    gain, _ = steady_sine_response(B.Notch(80.0, 40.0, FS), 80.0, FS, periods=400)
    assert 20 * np.log10(gain) < -40
    edge, _ = steady_sine_response(B.Notch(80.0, 40.0, FS), 5.0, FS)
    assert edge > 0.99


@pytest.mark.parametrize("kind,cutoff,bw", CASES)
def test_reset_then_constant_input_gives_no_glitch(kind, cutoff, bw):
    f = make(kind, cutoff, FS, bw)
    f.reset(3.25)
    y = f.apply(np.full(500, 3.25))
    np.testing.assert_allclose(y, 3.25, rtol=2e-6)


@pytest.mark.parametrize("kind,cutoff,bw", CASES)
def test_changing_the_cutoff_keeps_the_state(kind, cutoff, bw):
    f = make(kind, cutoff, FS, bw)
    f.reset(-1.5)
    f.apply(np.full(10, -1.5))
    assert f.update_cutoff(cutoff * 1.5, bw * 1.2) == 0
    np.testing.assert_allclose(f.apply(np.full(100, -1.5)), -1.5, rtol=2e-6)


@pytest.mark.parametrize("factory", [lambda: B.PT1(0, FS), lambda: B.PT2(0, FS),
                                     lambda: B.PT2x2(0, FS), lambda: B.BiquadLowPass(0, FS),
                                     lambda: B.Notch(0, 40, FS),
                                     lambda: B.Filter(B.lib.FC_FILTER_NONE, 20, FS)])
def test_cutoff_zero_is_pass_through(factory):
    x = np.random.default_rng(1).normal(size=300).astype(np.float32)
    np.testing.assert_array_equal(factory().apply(x), x)


def test_biquad_at_or_above_nyquist_is_refused_and_passes_through():
    f = B.BiquadLowPass(600.0, FS)
    assert f.init_status != 0
    x = np.linspace(-1, 1, 50, dtype=np.float32)
    np.testing.assert_array_equal(f.apply(x), x)
    n = B.Notch(480.0, 100.0, FS)   # upper edge beyond Nyquist
    assert n.init_status != 0


def test_unknown_kind_is_refused():
    assert B.Filter(42, 20.0, FS).init_status != 0


@pytest.mark.parametrize("n,correction", [(1, 1.0), (2, 1.553773974), (4, 2.298959223)])
def test_stage_gain_reduces_to_the_analog_cutoff_correction(n, correction):
    # For f << fs the exact discrete solution equals Betaflight's correction
    # 1/sqrt(2^(1/n) - 1) applied to a backward-Euler PT1 (k = w / (w + 1)).
    fs, fc = 32000.0, 10.0
    w = 2 * np.pi * fc * correction / fs
    assert stage_gain(fc, fs, n) == pytest.approx(w / (w + 1), rel=5e-3)  # O(w) apart
    assert correction == pytest.approx(1 / np.sqrt(2 ** (1 / n) - 1), rel=1e-8)
    f = {1: B.PT1, 2: B.PT2, 4: B.PT2x2}[n](fc, fs)
    x = np.zeros(4000)
    x[0] = 1.0
    b, a = ptn_ba(fc, fs, n)
    np.testing.assert_allclose(f.apply(x), signal.lfilter(b, a, x), atol=1e-6)


@pytest.mark.parametrize("fs", [32000.0, 100000.0])
def test_biquad_stays_accurate_at_oversampled_imu_rates(fs):
    # 20 Hz at 32-100 kHz puts the poles within 1e-3 of z = 1, where a plain
    # float32 direct form loses the response; fc_filter.c keeps d1, d2 exact.
    b, a = signal.butter(2, 20.0, fs=fs)
    for freq in (5.0, 20.0, 60.0):
        gain, _ = steady_sine_response(B.BiquadLowPass(20.0, fs), freq, fs, periods=40)
        _, h_ref = signal.freqz(b, a, worN=[freq], fs=fs)
        assert 20 * np.log10(gain) == pytest.approx(20 * np.log10(abs(h_ref[0])), abs=0.05)
    f = B.BiquadLowPass(20.0, fs)
    f.reset(0.3)
    noisy = 0.3 + np.random.default_rng(0).normal(0, 0.01, 40000)
    assert f.apply(noisy)[-20000:].mean() == pytest.approx(0.3, rel=3e-3)
