"""fc_ins.c: the IMU front end (gyro/accel low-pass, optional gyro notch)."""

import numpy as np
from scipy import signal

import fc_blocks as B

FS = 1000.0
G = np.array([0.0, 0.0, -9.80665])


def test_first_sample_primes_the_filters():
    ins = B.InsFrontEnd(FS)
    acc = np.tile(G, (50, 1))
    gyro = np.tile([0.1, -0.2, 0.05], (50, 1))
    g_f, a_f, st = ins.run(acc, gyro)
    assert (st == 0).all()
    np.testing.assert_allclose(a_f, acc, rtol=1e-6)
    np.testing.assert_allclose(g_f, gyro, rtol=1e-6)


def test_gyro_lowpass_is_the_butterworth_of_ins_gyro_filter():
    ins = B.InsFrontEnd(FS, gyro_cutoff_hz=20.0, accel_cutoff_hz=10.0)
    rng = np.random.default_rng(3)
    gyro = rng.normal(size=(400, 3)).astype(np.float32)
    gyro[0] = 0.0   # primed at 0: same start as lfilter's zero state
    acc = np.tile(G, (400, 1))
    g_f, _, _ = ins.run(acc, gyro)
    b, a = signal.butter(2, 20.0, fs=FS)
    np.testing.assert_allclose(g_f[:, 1], signal.lfilter(b, a, gyro[:, 1]), atol=1e-5)


def test_notch_only_when_enabled():
    t = np.arange(2000) / FS
    tone = 0.5 * np.sin(2 * np.pi * 80.0 * t)
    gyro = np.stack([tone, tone, tone], axis=1)
    acc = np.tile(G, (len(t), 1))
    off, _, _ = B.InsFrontEnd(FS, gyro_cutoff_hz=0.0).run(acc, gyro)
    on, _, _ = B.InsFrontEnd(FS, gyro_cutoff_hz=0.0, notch=True, notch_hz=80.0,
                             notch_bw_hz=40.0).run(acc, gyro)
    assert np.abs(off[-500:, 0]).max() > 0.45
    assert np.abs(on[-500:, 0]).max() < 0.01


def test_non_finite_samples_are_refused_and_outputs_hold():
    ins = B.InsFrontEnd(FS)
    acc = np.tile(G, (6, 1)).astype(np.float32)
    gyro = np.zeros((6, 3), np.float32)
    acc[2, 0] = np.nan
    gyro[4, 2] = np.inf
    g_f, a_f, st = ins.run(acc, gyro)
    assert list(st) == [0, 0, -3, 0, -3, 0]
    assert np.isfinite(g_f).all() and np.isfinite(a_f).all()
    np.testing.assert_array_equal(a_f[2], a_f[1])
