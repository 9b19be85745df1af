"""fc_mixer.c: quad-X mixing, saturation flags, yaw headroom, clamp, slew."""

import numpy as np
import pytest

import fc_blocks as B
from silbridge.fc_sil.status import SAT_PITCH, SAT_ROLL, SAT_THR_HIGH, SAT_THR_LOW, SAT_YAW


def test_arducopter_quad_x_order_and_directions():
    # motor 1 front-right CCW, 2 back-left CCW, 3 front-left CW, 4 back-right CW
    f = np.array(B.Mixer.factors())
    np.testing.assert_array_equal(f[:, 0], [-1, 1, 1, -1])   # roll right: left side up
    np.testing.assert_array_equal(f[:, 1], [1, -1, 1, -1])   # pitch up: front up
    np.testing.assert_array_equal(f[:, 2], [1, 1, -1, -1])   # yaw right: CCW motors up
    motor, pwm, flags, _ = B.Mixer(slew=False).run(1500, 20, 0, 0)
    np.testing.assert_array_equal(pwm[0], [1480, 1520, 1520, 1480])
    assert flags[0] == 0


def test_roll_pitch_saturation_scales_both_and_flags_them():
    motor, pwm, flags, applied = B.Mixer(slew=False).run(1500, 500, 300, 0)
    assert flags[0] & SAT_ROLL and flags[0] & SAT_PITCH
    assert motor.min() >= 1150 - 1e-3 and motor.max() <= 1950 + 1e-3   # MOT_SPIN_MIN..MAX band
    assert applied[0, 1] / applied[0, 2] == pytest.approx(500 / 300)     # ratio kept


def test_throttle_gives_way_and_flags_its_limits():
    _, _, flags, applied = B.Mixer(slew=False).run(1940, 100, 0, 0)
    assert flags[0] & SAT_THR_HIGH and not flags[0] & SAT_ROLL
    assert applied[0, 0] == pytest.approx(1850)
    _, _, flags, _ = B.Mixer(slew=False).run(1100, 0, 0, 0)
    assert flags[0] & SAT_THR_LOW


def test_yaw_keeps_its_headroom_and_is_flagged_beyond_it():
    _, _, flags, applied = B.Mixer(yaw_headroom_us=200, slew=False).run(1550, 380, 0, 500)
    assert flags[0] & SAT_YAW
    assert applied[0, 3] == pytest.approx(200)     # the room left is smaller: headroom wins
    _, _, flags, applied = B.Mixer(slew=False).run(1500, 0, 0, 150)
    assert not flags[0] & SAT_YAW and applied[0, 3] == pytest.approx(150)


def test_outputs_stay_in_range_and_finite_for_any_input():
    rng = np.random.default_rng(5)
    n = 5000
    thr = rng.uniform(0, 3000, n).astype(np.float32)
    cols = [rng.normal(0, 800, n).astype(np.float32) for _ in range(3)]
    cols[0][::7] = np.nan
    cols[1][::11] = np.inf
    thr[::13] = -np.inf
    motor, pwm, flags, _ = B.Mixer(slew=False).run(thr, *cols)
    assert np.isfinite(motor).all()
    assert pwm.min() >= 1000 and pwm.max() <= 2000


def test_slew_limit_per_motor():
    m = B.Mixer(slew_up_time_s=0.05, slew_dn_time_s=0.1)
    _, pwm, _, _ = m.run(np.full(40, 1900.0), 0, 0, 0, dt_s=0.0025)
    steps = np.diff(np.vstack([[1000] * 4, pwm]).astype(int), axis=0)
    assert steps.max() == 50           # 1000 us in 0.05 s at 400 Hz
    assert pwm[-1, 0] == 1900
    _, pwm, _, _ = m.run(np.full(40, 1200.0), 0, 0, 0, dt_s=0.0025)
    assert np.diff(np.vstack([[1900] * 4, pwm]).astype(int), axis=0).min() == -25
    m_off = B.Mixer(slew_up_time_s=0.05, slew=False)
    _, pwm, _, _ = m_off.run(1900.0, 0, 0, 0)
    assert pwm[0, 0] == 1900


def test_spool_states():
    m = B.Mixer(slew=False)
    _, pwm, flags, _ = m.run(1500, 100, 100, 100, spool=B.Mixer.SPOOL_SHUT_DOWN)
    assert np.all(pwm == 1000) and flags[0] == 0
    _, pwm, _, _ = m.run(1100, 100, 100, 100, spool=B.Mixer.SPOOL_GROUND_IDLE)
    assert np.all(pwm == 1100)


def test_saturated_roll_pitch_fit_around_the_demanded_collective_up_to_half_thrust():
    # ArduCopter's rpy_scale: the altitude loop keeps its say while roll and pitch saturate
    # (band 1150..1950; half thrust at 1150 + 0.648 x 800; below the middle, halfway to it)
    lo, hi, half = 1150.0, 1950.0, 1150.0 + 0.648 * 800.0
    for demand, collective in ((1620, 1620), (1900, half), (1250, 1400), (1550, 1550)):
        motor, _, flags, applied = B.Mixer(slew=False).run(demand, 600, 500, 0)
        assert flags[0] & SAT_ROLL and flags[0] & SAT_PITCH
        assert applied[0, 0] == pytest.approx(collective, abs=0.05), demand
        assert motor[0].mean() == pytest.approx(collective, abs=0.05)
        assert motor.min() >= lo - 1e-3 and motor.max() <= hi + 1e-3
        assert applied[0, 1] / applied[0, 2] == pytest.approx(600 / 500)   # ratio kept
        edge = hi - motor.max() if collective >= 1550 else motor.min() - lo
        assert edge == pytest.approx(0.0, abs=0.05)    # as much authority as fits
