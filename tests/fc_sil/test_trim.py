"""fc_trim.c: hover-trim learning, saturation and ramp-in (paper 3.7)."""

import numpy as np
import pytest

import fc_blocks as B

DT = 0.001


def run(trim, airborne_from, n, ex=0.1, ey=-0.2):
    air = (np.arange(n) >= airborne_from).astype(np.uint8)
    return trim.run(air, np.full(n, ex), np.full(n, ey), DT)


def test_learns_the_mean_error_over_the_window_then_ramps_in():
    out = run(B.HoverTrim(ramp=True), airborne_from=500, n=6000)   # the paper's ramp (off by default)
    assert np.all(out[:3500] == 0.0)                     # nothing until window + lift-off
    learned = np.array([80 * 0.1, 80 * -0.2])            # 80 us/rad times the mean error
    half = 500 + 3000 + 400                              # half way through the 0.8 s ramp
    np.testing.assert_allclose(out[half], 0.5 * learned, atol=0.15)
    np.testing.assert_allclose(out[-1], learned, rtol=1e-4)
    steps = np.abs(np.diff(out, axis=0)).max(axis=0)
    assert np.all(steps <= np.abs(learned) * DT / 0.8 * 1.01)  # linear ramp, no step


def test_saturates_at_the_limit():
    out = run(B.HoverTrim(), 0, 5000, ex=2.0, ey=-2.0)
    np.testing.assert_allclose(out[-1], [50.0, -50.0])


def test_without_ramp_the_trim_is_a_step():
    out = run(B.HoverTrim(ramp=False), 0, 4000)
    first = np.argmax(out[:, 0] != 0)
    assert out[first, 0] == pytest.approx(8.0, rel=1e-4)


def test_disabled_trim_stays_zero():
    assert np.all(run(B.HoverTrim(enable=False), 0, 5000) == 0.0)
