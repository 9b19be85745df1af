"""fc_rate_pid.c: rate PI + D on measurement (paper 3.6, ArduPilot AC_PID rules)."""

import numpy as np
import pytest

import fc_blocks as B

LOOP_HZ = 1000.0
P, I, D, FF, OUT, LIMITED, DCLAMPED = range(7)


def pid(**kw):
    # These tests pin the PID law on the raw target: no target low-pass unless a test asks.
    kw.setdefault("fltt_hz", 0.0)
    return B.RatePID(LOOP_HZ, **kw)


def test_p_and_ff_in_microseconds():
    out = pid(kp=0.1, ki=0.0, kd=0.0, kff=0.05).run(np.full(10, 2.0), np.full(10, 0.5))
    assert out[-1, P] == pytest.approx(0.1 * 1.5 * 500, rel=1e-6)
    assert out[-1, FF] == pytest.approx(0.05 * 2.0 * 500, rel=1e-6)
    assert out[-1, OUT] == pytest.approx(out[-1, P] + out[-1, FF] + out[-1, I] + out[-1, D])


def test_d_is_on_measurement_and_opposes_its_rate_of_change():
    n = 400
    meas = np.concatenate([np.zeros(100), np.linspace(0, 3.0, n - 100)])  # rate rising
    out = pid(kp=0, ki=0, kd=0.0036, fltd_hz=0.0, d_clamp=False).run(np.zeros(n), meas)
    slope = 3.0 / (n - 101) * LOOP_HZ  # rad/s^2
    assert out[-1, D] == pytest.approx(-0.0036 * slope * 500, rel=1e-3)
    assert out[-1, D] < 0
    # A target step gives no derivative kick.
    tgt = np.concatenate([np.zeros(50), np.full(50, 5.0)])
    out = pid(kp=0, ki=0, d_clamp=False).run(tgt, np.zeros(100))
    assert np.all(out[:, D] == 0.0)


def test_d_clamp_limits_the_d_term():
    meas = np.concatenate([np.zeros(10), np.full(10, 2.0)])       # a rate step
    clamped = pid(kp=0, ki=0, fltd_hz=0.0).run(np.zeros(20), meas)
    free = pid(kp=0, ki=0, fltd_hz=0.0, d_clamp=False).run(np.zeros(20), meas)
    assert free[10, D] == pytest.approx(-0.0036 * 2.0 * LOOP_HZ * 500, rel=1e-5)
    assert clamped[10, D] == pytest.approx(-12.0)
    assert clamped[10, DCLAMPED] == 1.0
    assert np.abs(clamped[:, D]).max() <= 12.0


def test_pt2x2_d_filter_smooths_more_than_pt1():
    rng = np.random.default_rng(7)
    meas = rng.normal(0, 0.05, 5000)
    pt2x2 = pid(kp=0, ki=0, d_clamp=False, d_pt2x2=True).run(np.zeros(5000), meas)
    pt1 = pid(kp=0, ki=0, d_clamp=False, d_pt2x2=False).run(np.zeros(5000), meas)
    assert np.std(pt2x2[1000:, D]) < 0.5 * np.std(pt1[1000:, D])


def test_integrator_clamped_at_imax():
    out = pid(kp=0, ki=1.0, kd=0, imax=0.2).run(np.full(2000, 1.0), np.zeros(2000))
    assert out[99, I] == pytest.approx(1.0 * 0.1 * 500, rel=1e-3)   # ki e t, in us
    assert out[-1, I] == pytest.approx(0.2 * 500)
    assert out[-1, LIMITED] == 1.0


def test_integrator_may_shrink_but_not_grow_while_saturated():
    p = pid(kp=0, ki=1.0, kd=0, imax=0.5)
    p.run(np.full(100, 1.0), np.zeros(100))                 # I = 50 us
    grow = p.run(np.full(100, 1.0), np.zeros(100), limit=1)
    assert np.all(grow[:, I] == pytest.approx(50.0, rel=1e-3))
    assert np.all(grow[:, LIMITED] == 1.0)
    shrink = p.run(np.full(100, -1.0), np.zeros(100), limit=1)
    assert shrink[-1, I] == pytest.approx(0.0, abs=0.1)
    # ... and it may not grow on the negative side either
    more = p.run(np.full(100, -1.0), np.zeros(100), limit=1)
    assert more[-1, I] == pytest.approx(shrink[-1, I], abs=1e-4)


def test_without_antiwindup_the_integrator_grows_through_saturation():
    p = pid(kp=0, ki=1.0, kd=0, imax=0.1, antiwindup=False)
    out = p.run(np.full(800, 1.0), np.zeros(800), limit=1)
    assert out[-1, I] == pytest.approx(0.8 * 500, rel=1e-3)     # past IMAX, ignoring the limit
    out = p.run(np.full(800, 1.0), np.zeros(800), limit=1)
    assert out[-1, I] == pytest.approx(1.0 * 500)               # bounded by full authority


def test_no_integration_unless_asked():
    out = pid(ki=1.0).run(np.full(100, 1.0), np.zeros(100), integrate=False)
    assert np.all(out[:, I] == 0.0)


def test_reset_then_constant_input_gives_no_glitch():
    out = pid(fltt_hz=20, flte_hz=5).run(np.full(500, 0.3), np.full(500, 0.3))
    assert np.all(out[:, [P, D, I]] == 0.0)
    out = pid(fltt_hz=20, flte_hz=5, ki=0).run(np.full(500, 0.5), np.full(500, 0.3))
    np.testing.assert_allclose(out[:, P], 0.135 * 0.2 * 500, rtol=1e-5)


def test_non_finite_inputs_keep_the_previous_output():
    p = pid()
    first = p.run(np.full(10, 0.2), np.zeros(10))
    out = p.run(np.array([np.nan, 0.2, np.inf]), np.array([0.0, np.nan, 0.0]))
    assert np.isfinite(out).all()
    assert np.all(out[:, OUT] == first[-1, OUT])
    assert p.run([0.2], [0.0])[0, OUT] > first[-1, OUT]   # and carries on afterwards


def test_the_period_enters_through_the_step_only():
    """Stepped at another period than the one it was built for, the PID recomputes its
    filters for the step's period (fc_rate_pid_update): it then equals one built for it."""
    rng = np.random.default_rng(5)
    tgt, meas = rng.normal(size=300), rng.normal(size=300)
    kw = dict(fltt_hz=20.0, flte_hz=30.0, fltd_hz=40.0, d_clamp=False)
    moved = pid(**kw)
    moved.dt_s = 1.0 / 400.0
    built = B.RatePID(400.0, **kw)
    np.testing.assert_array_equal(moved.run(tgt, meas), built.run(tgt, meas))
    # Within FC_RETUNE_TOLERANCE (1 %) the filters keep their period.
    near = pid(**kw)
    near.dt_s = 1.0 / LOOP_HZ * 1.005
    assert not np.array_equal(near.run(tgt, meas), B.RatePID(LOOP_HZ / 1.005, **kw).run(tgt, meas))
