"""fc_shaper.c and the shaped attitude stage: ArduCopter-style input shaping.

The target moves toward a commanded attitude with a square-root profile bounded
by ATC_ACCEL_*_MAX, ends in an ATC_INPUT_TC exponential, respects
ATC_RATE_*_MAX, and its angular velocity is fed forward into the rate loop
(ATC_RATE_FF_ENAB). Zero limits behave as ArduCopter's.
"""

import math

import numpy as np
import pytest

import fc_blocks as B
from silbridge.fc_sil.flight_core import FlightCore

LOOP_HZ = 8000.0
DT = 1.0 / LOOP_HZ
ACCEL_RP = math.radians(1100.0)     # ATC_ACCEL_R/P_MAX 110000 cdeg/s^2 [rad/s^2]
ACCEL_Y = math.radians(270.0)       # ATC_ACCEL_Y_MAX 27000 cdeg/s^2
TC = 0.15                           # ATC_INPUT_TC
STEP = math.radians(30.0)


def first_time(mask):
    idx = np.flatnonzero(mask)
    return idx[0] * DT if len(idx) else math.inf


# ---- sqrt controller ----------------------------------------------------------------

def test_sqrt_controller_is_linear_then_square_root_and_continuous():
    p, a = 1.0 / TC, ACCEL_RP
    linear_dist = a / p ** 2
    assert B.sqrt_controller(0.1, p, a, 0.0) == pytest.approx(0.1 * p, rel=1e-6)
    e = 2.0 * linear_dist
    assert B.sqrt_controller(e, p, a, 0.0) == pytest.approx(
        math.sqrt(2 * a * (e - linear_dist / 2)), rel=1e-6)
    assert B.sqrt_controller(-e, p, a, 0.0) == pytest.approx(
        -math.sqrt(2 * a * (e - linear_dist / 2)), rel=1e-6)
    # both pieces meet at the boundary, with the same slope p
    lo = B.sqrt_controller(linear_dist * 0.9999, p, a, 0.0)
    hi = B.sqrt_controller(linear_dist * 1.0001, p, a, 0.0)
    assert hi == pytest.approx(lo, rel=1e-3)
    # p = 0: pure sqrt; limit 0: pure linear; never past zero within one step
    assert B.sqrt_controller(0.5, 0.0, a, 0.0) == pytest.approx(math.sqrt(2 * a * 0.5), rel=1e-6)
    assert B.sqrt_controller(0.5, p, 0.0, 0.0) == pytest.approx(0.5 * p, rel=1e-6)
    assert B.sqrt_controller(1e-7, 0.0, a, DT) == pytest.approx(1e-7 / DT, rel=1e-5)


# ---- the shaped target ------------------------------------------------------------

def test_30_deg_step_reaches_without_overshoot_within_the_accel_limited_time():
    out = B.Shaper(LOOP_HZ).run(STEP, n=int(1.5 * LOOP_HZ))
    roll, rate = out[:, 0], out[:, 3]
    assert roll.max() <= STEP + 1e-6                     # no overshoot
    assert np.all(np.diff(roll) >= -1e-7)                # monotone
    assert np.all(rate >= -1e-6)                         # never turns back
    # Bang-bang at the accel limit would take 2 sqrt(step / a) (0.33 s); the
    # last stretch is the ATC_INPUT_TC exponential, ln(100) tc to within 1 %.
    t_bound = 2.0 * math.sqrt(STEP / ACCEL_RP) + math.log(100.0) * TC
    t_1pct = first_time(np.abs(STEP - roll) <= 0.01 * STEP)
    assert t_1pct <= t_bound
    # ...and not faster than the acceleration limit allows at all
    assert t_1pct >= 2.0 * math.sqrt(0.99 * STEP / ACCEL_RP) * 0.99
    assert roll[-1] == pytest.approx(STEP, abs=math.radians(0.01))


def test_target_acceleration_respects_atc_accel_max():
    for accel_cdeg, cmd in ((110000.0, STEP), (30000.0, -STEP), (72000.0, math.radians(10))):
        s = B.Shaper(LOOP_HZ, accel_max_cdeg_s2=(accel_cdeg, accel_cdeg, 27000.0))
        out = s.run(0.0, pitch_rad=cmd, n=int(2.0 * LOOP_HZ))
        a = np.abs(np.diff(out[:, 4])) / DT
        limit = math.radians(accel_cdeg * 0.01)
        assert a.max() <= limit * (1 + 1e-3)
        assert a.max() >= 0.95 * limit                   # the limit is what shapes the start
        assert out[-1, 1] == pytest.approx(cmd, abs=math.radians(0.01))


def test_target_rate_respects_atc_rate_max():
    # roll alone
    out = B.Shaper(LOOP_HZ, rate_max_deg_s=(60.0, 0.0, 0.0)).run(STEP, n=int(2 * LOOP_HZ))
    assert np.degrees(np.abs(out[:, 6])).max() <= 60.0 + 1e-3
    assert np.degrees(np.abs(out[:, 6])).max() >= 59.0
    assert out[-1, 0] == pytest.approx(STEP, abs=math.radians(0.05))
    # roll and pitch together stay on the ellipse of both limits
    out = B.Shaper(LOOP_HZ, rate_max_deg_s=(60.0, 40.0, 0.0)).run(STEP, pitch_rad=STEP,
                                                                   n=int(2 * LOOP_HZ))
    norm = np.hypot(np.degrees(out[:, 6]) / 60.0, np.degrees(out[:, 7]) / 40.0)
    assert norm.max() <= 1.0 + 1e-4
    assert norm.max() >= 0.99


def test_zero_tc_and_zero_accel_pass_through():
    s = B.Shaper(LOOP_HZ, input_tc_s=0.0, accel_max_cdeg_s2=(0.0, 0.0, 0.0))
    out = s.run(STEP, pitch_rad=-0.2, n=5)
    np.testing.assert_allclose(out[:, 0], STEP, atol=1e-7)
    np.testing.assert_allclose(out[:, 1], -0.2, atol=1e-7)
    assert np.all(out[:, 3:] == 0.0)                     # a step has no rate to feed forward


def test_zero_accel_is_a_first_order_lag_of_atc_input_tc():
    out = B.Shaper(LOOP_HZ, accel_max_cdeg_s2=(0.0, 0.0, 0.0)).run(STEP, n=int(LOOP_HZ))
    assert out[0, 3] == pytest.approx(STEP / TC, rel=1e-4)   # no acceleration limit
    i_tc = int(round(TC * LOOP_HZ))
    assert out[i_tc, 0] == pytest.approx(STEP * (1 - math.exp(-1)), rel=2e-3)


def test_zero_tc_with_accel_limit_is_the_square_root_profile_with_a_10_ms_tail():
    out = B.Shaper(LOOP_HZ, input_tc_s=0.0).run(STEP, n=int(LOOP_HZ))
    # ArduCopter floors ATC_INPUT_TC at 10 ms: nearly bang-bang at the accel limit
    t_1pct = first_time(out[:, 0] >= 0.99 * STEP)
    t_bang = 2.0 * math.sqrt(STEP / ACCEL_RP)
    assert 0.9 * t_bang <= t_1pct <= t_bang + math.log(100.0) * 0.01
    assert out[:, 0].max() <= STEP + 1e-6


def test_disabled_shaper_is_the_command():
    s = B.Shaper(LOOP_HZ, enable=False)
    out = s.run(STEP, pitch_rad=0.1, yaw_rad=0.4, hold_yaw=True, n=3)
    np.testing.assert_allclose(out[:, :3], [[STEP, 0.1, 0.4]] * 3, atol=1e-7)
    assert np.all(out[:, 3:] == 0.0)


def test_held_yaw_is_shaped_at_the_yaw_accel_limit_and_rate_mode_slews():
    out = B.Shaper(LOOP_HZ).run(0.0, yaw_rad=1.0, hold_yaw=True, n=int(3 * LOOP_HZ))
    a = np.abs(np.diff(out[:, 5])) / DT
    assert a.max() <= ACCEL_Y * (1 + 1e-3)
    assert out[:, 2].max() <= 1.0 + 1e-6
    assert out[-1, 2] == pytest.approx(1.0, abs=1e-3)
    # rate mode: the yaw rate reaches the command in rate / accel
    out = B.Shaper(LOOP_HZ).run(0.0, yaw_rate_rad_s=1.0, n=int(0.5 * LOOP_HZ))
    assert first_time(out[:, 5] >= 1.0 - 1e-5) == pytest.approx(1.0 / ACCEL_Y, abs=2 * DT)
    assert out[-1, 8] == pytest.approx(1.0, abs=1e-5)     # level: body r = yaw rate


def test_euler_rates_and_body_rates_at_a_tilt():
    # Rolled 35 deg, a pitch (Euler) rate needs body q and r both: the yaw
    # acceleration limit then caps the pitch-axis acceleration (euler_accel_limit).
    s = B.Shaper(LOOP_HZ, euler0_rad=(math.radians(35.0), 0.0, 0.0))
    out = s.run(math.radians(35.0), pitch_rad=STEP, n=int(1.5 * LOOP_HZ))
    a_pitch = np.abs(np.diff(out[:, 4])) / DT
    expect = min(ACCEL_RP / math.cos(math.radians(35)), ACCEL_Y / math.sin(math.radians(35)))
    assert a_pitch.max() <= expect * (1 + 2e-3)
    assert a_pitch.max() >= 0.9 * expect
    roll = out[:, 0]
    i = int(0.2 * LOOP_HZ)
    q_expect = math.cos(roll[i]) * out[i, 4] + math.sin(roll[i]) * math.cos(out[i, 1]) * out[i, 5]
    assert out[i, 7] == pytest.approx(q_expect, rel=1e-4)


# ---- rate targets with feed-forward -----------------------------------------------------

def q_axis(axis, angle):
    q = [math.cos(angle / 2), 0.0, 0.0, 0.0]
    q[1 + axis] = math.sin(angle / 2)
    return q


def test_feed_forward_adds_the_target_rate_rotated_into_the_body():
    r, fade = B.rate_targets_ff((0.01, -0.02, 0.0), (1, 0, 0, 0), (0.5, 0.2, 0.1))
    assert fade == 1.0
    assert r == pytest.approx((4.5 * 0.01 + 0.5, -4.5 * 0.02 + 0.2, 0.1), abs=1e-6)
    # the target is yawed 90 deg from the body: its x rate is the body's y rate
    r, _ = B.rate_targets_ff((0, 0, 0), q_axis(2, math.pi / 2), (0.5, 0.0, 0.0))
    assert r == pytest.approx((0.0, 0.5, 0.0), abs=1e-6)
    # ATC_RATE_*_MAX limits the P part (ArduCopter: the feed-forward is limited in the shaper)
    r, _ = B.rate_targets_ff((1.0, 0.0, 0.0), (1, 0, 0, 0), (0.3, 0, 0),
                             rate_max_rad_s=(1.0, 0.0, 0.0))
    assert r[0] == pytest.approx(1.3, abs=1e-6)


def test_feed_forward_fades_out_with_a_large_thrust_error():
    ff = (0.5, 0.5, 0.4)
    _, fade = B.rate_targets_ff((0, 0, 0), q_axis(0, math.radians(45)), ff, gyro_z_rad_s=0.7)
    assert fade == pytest.approx(0.5, abs=1e-4)
    r, fade = B.rate_targets_ff((0, 0, 0), q_axis(0, math.radians(70)), ff, gyro_z_rad_s=0.7)
    assert fade == 0.0
    assert r[0] == 0.0 and r[1] == 0.0 and r[2] == pytest.approx(0.7)   # tilt first


# ---- the core: shaped status target, FF on/off ----------------------------------------------

def fly_step(stream, params):
    fc = FlightCore(params)
    s = stream(imu_hz=1000)
    fc.arm()
    fc.set_throttle(0.5)                  # spool to flight at once (no altitude loop needed)
    fc.step_batch(s.batch(200))
    fc.set_attitude_target(STEP, 0.0, yaw_rate_rad_s=0.0)
    _, st = fc.step_batch(s.batch(400))   # 0.4 s, the vehicle "level" (still IMU)
    return st


def test_core_status_target_is_the_shaped_target_with_feed_forward(stream):
    st = fly_step(stream, {})
    roll_t = st["att_target_rad"][:, 0]
    assert roll_t[0] < math.radians(0.1) and roll_t[2] > 0.0   # the step is not taken raw
    assert np.all(np.diff(roll_t) >= -1e-7) and roll_t.max() <= STEP + 1e-6
    # PWM ticks every 2.5 ms sample the shaped target of the 1 kHz rate loop;
    # a tick is stepped at the first IMU sample at or after it.
    ref = B.Shaper(1000.0).run(STEP, n=400)
    idx = np.ceil(np.arange(len(st)) * 2.5).astype(int)
    np.testing.assert_allclose(roll_t, ref[idx, 0], atol=1e-5)
    # the rate target is the P part plus the target's own angular velocity
    r = st["rate_target_frd_rad_s"][:, 0]
    e = st["att_error_frd_rad"][:, 0]
    np.testing.assert_allclose(r - 4.5 * e, ref[idx, 6], atol=1e-4)
    assert ref[idx, 6].max() > 1.0


def test_core_feed_forward_off_takes_the_raw_step_like_the_ablation_switch(stream):
    off = fly_step(stream, {"ATC_RATE_FF_ENAB": 0})
    np.testing.assert_allclose(off["att_target_rad"][:, 0], STEP, atol=1e-6)
    np.testing.assert_allclose(off["rate_target_frd_rad_s"][:, 0],
                               4.5 * off["att_error_frd_rad"][:, 0], atol=1e-5)
    ablated = fly_step(stream, {"SB_SHAPE_EN": 0})
    assert ablated.tobytes() == off.tobytes()


def test_shaping_parameters_have_arducopter_names_and_defaults():
    fc = FlightCore()
    expect = {"ATC_INPUT_TC": 0.15, "ATC_ACCEL_R_MAX": 110000, "ATC_ACCEL_P_MAX": 110000,
              "ATC_ACCEL_Y_MAX": 27000, "ATC_RATE_FF_ENAB": 1, "SB_SHAPE_EN": 1}
    for name, value in expect.items():
        assert fc.get_param(name) == pytest.approx(value), name
