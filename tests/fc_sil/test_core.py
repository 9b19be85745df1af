"""fc_core.c through FlightCore: record batches in, PWM records and status out."""

import numpy as np
import pytest

from silbridge.fc_sil import STATUS_DTYPE
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.errors import InputError
from silbridge.fc_sil.status import SPOOL_GROUND_IDLE, SPOOL_SHUT_DOWN
from silbridge.shm import records as R


def test_pwm_ticks_on_the_sim_time_grid(stream):
    fc = FlightCore()
    s = stream(imu_hz=1000)
    recs = s.batch(101)                        # IMU at 0..100 ms
    pwm, st = fc.step_batch(recs)
    assert pwm.dtype == R.PWM_DTYPE and st.dtype == STATUS_DTYPE
    assert len(pwm) == 41                      # ticks 0, 2.5, ..., 100 ms
    np.testing.assert_array_equal(pwm["sim_ns"], np.arange(41) * 2_500_000)
    np.testing.assert_array_equal(pwm["seq"], np.arange(41))
    assert np.all(pwm["kind"] == R.Kind.PWM)
    assert np.all(pwm["channel_count"] == 4)
    assert np.all(pwm["imu_sim_ns"] >= pwm["sim_ns"])
    assert np.all(pwm["imu_sim_ns"] - pwm["sim_ns"] < 1_000_000)   # the first IMU at/after
    assert np.all(pwm["wall_ns"] > 0)
    np.testing.assert_array_equal(st["sim_ns"], pwm["sim_ns"])
    # fc_step_seq is the seq of the last consumed sensor record
    imu_seq_at = pwm["imu_sim_ns"] // 1_000_000
    assert np.all(pwm["fc_step_seq"] <= imu_seq_at + 10)
    # disarmed: every output at MOT_PWM_MIN
    assert np.all(pwm["pwm_us"][:, :4] == 1000) and np.all(pwm["armed"] == 0)
    assert np.all(st["spool"] == SPOOL_SHUT_DOWN)
    # the next batch continues the grid
    pwm2, _ = fc.step_batch(s.batch(10))
    np.testing.assert_array_equal(pwm2["sim_ns"], [102_500_000, 105_000_000, 107_500_000,
                                                   110_000_000])


def test_batching_does_not_change_the_result(stream):
    s = stream(gt=True)
    recs = s.batch(3000)
    a, b = FlightCore(), FlightCore()
    for fc in (a, b):
        fc.arm()
        fc.set_attitude_target(0.1, -0.05, yaw_rate_rad_s=0.2)
    pa, sa = a.step_batch(recs)
    parts_p, parts_s = [], []
    for chunk in np.array_split(recs, [1, 2, 17, 400, 401, 1500, 2999]):
        p, st = b.step_batch(chunk)
        parts_p.append(p)
        parts_s.append(st)
    pb, sb = np.concatenate(parts_p), np.concatenate(parts_s)
    assert sa.tobytes() == sb.tobytes()
    for name in R.PWM_DTYPE.names:
        if name != "wall_ns":
            np.testing.assert_array_equal(pa[name], pb[name])


def test_preallocated_outputs(stream):
    fc = FlightCore()
    recs = stream().batch(50)
    n = fc.pwm_bound(recs)
    assert n == 20
    pwm_out = np.zeros(n, R.PWM_DTYPE)
    st_out = np.zeros(n, STATUS_DTYPE)
    pwm, st = fc.step_batch(recs, pwm_out, st_out)
    assert len(pwm) == 20 and np.shares_memory(pwm, pwm_out)
    with pytest.raises(ValueError, match="pwm_bound"):
        fc.step_batch(stream().batch(100), pwm_out[:3], st_out[:3])


def test_armed_on_the_ground_idles_at_spin_arm(stream):
    fc = FlightCore()
    fc.arm()
    fc.set_altitude_target(0.0)
    pwm, st = fc.step_batch(stream().batch(2000))
    assert np.all(st["spool"][1:] == SPOOL_GROUND_IDLE)
    # MOT_SPIN_ARM 0.10 of the range, reached through the slew limit
    assert np.all(pwm["pwm_us"][-1, :4] == 1100)
    assert np.all(st["airborne"] == 0) and np.all(st["pid_i"] == 0)


def test_setpoint_records_set_the_targets(stream, make_setpoint):
    fc = FlightCore()
    recs = np.concatenate([stream().batch(3),
                           make_setpoint(3_000_000, roll=0.1, pitch=-0.2, mask=1),
                           make_setpoint(3_000_000, alt=7.5, mask=2),
                           make_setpoint(3_000_000, yaw=1.0, mask=4),
                           make_setpoint(3_000_000, alt=float("nan"), mask=2)])
    fc.step_batch(recs)
    inp = fc.inputs()
    assert inp["roll_target_rad"] == pytest.approx(0.1)
    assert inp["pitch_target_rad"] == pytest.approx(-0.2)
    assert inp["alt_target_m"] == pytest.approx(7.5)     # NaN altitude means keep
    assert inp["yaw_target_rad"] == pytest.approx(1.0) and inp["yaw_hold"]


def test_nan_and_inf_inputs_never_reach_the_outputs(stream, make_setpoint):
    rng = np.random.default_rng(11)
    s = stream(gt=True)
    fc = FlightCore()
    fc.arm()
    fc.set_altitude_target(3.0)
    bad = (np.nan, np.inf, -np.inf)
    for _ in range(20):
        recs = s.batch(200)
        # Corrupt random float fields of random records of every kind.
        for kind, dtype in R.DTYPES.items():
            idx = np.flatnonzero(recs["kind"] == kind)
            if not len(idx):
                continue
            view = recs.view(dtype)
            for name in dtype.names:
                if dtype[name].base.kind == "f":
                    pick = rng.choice(idx, size=max(1, len(idx) // 5))
                    view[name][pick] = rng.choice(bad)
        recs = np.concatenate([recs, make_setpoint(int(recs["sim_ns"].max()), roll=np.nan,
                                                   pitch=np.inf, yaw=np.nan, alt=np.inf,
                                                   mask=7)])
        pwm, st = fc.step_batch(recs)
        for name in STATUS_DTYPE.names:
            if STATUS_DTYPE[name].base.kind == "f":
                assert np.isfinite(st[name]).all(), name
        assert pwm["pwm_us"][:, :4].min() >= 1000 and pwm["pwm_us"][:, :4].max() <= 2000
    assert fc.counters()["rejected"] > 0
    assert fc.inputs()["alt_target_m"] == pytest.approx(3.0)


def test_oversampled_imu_decimates_the_rate_loop(stream):
    fc = FlightCore()
    pwm, st = fc.step_batch(stream(imu_hz=32000, baro_hz=100, mag_hz=100).batch(32000))
    c = fc.counters()
    assert c["imu"] == 32000
    assert c["rate_loop"] == pytest.approx(8000, abs=2)   # SB_LOOP_HZ = 8000
    assert len(pwm) == 400
    fc1 = FlightCore()
    fc1.step_batch(stream(imu_hz=1000).batch(1000))
    assert fc1.counters()["rate_loop"] == 999             # every sample after the first


def test_time_must_advance(stream):
    fc = FlightCore()
    recs = stream().batch(10)
    fc.step_batch(recs)
    fc.step_batch(recs[recs["kind"] == R.Kind.IMU][:3])   # replayed: refused
    assert fc.counters()["rejected"] == 3


def test_pwm_rate_parameter_takes_effect_at_once(stream):
    fc = FlightCore()
    s = stream()
    fc.step_batch(s.batch(10))
    fc.set_param("SB_PWM_HZ", 200)
    pwm, _ = fc.step_batch(s.batch(30))
    assert np.all(np.diff(pwm["sim_ns"]) == 5_000_000)


def test_targets_are_validated():
    fc = FlightCore()
    with pytest.raises(InputError):
        fc.set_attitude_target(np.nan, 0.0)
    with pytest.raises(InputError):
        fc.set_throttle(1.5)
    with pytest.raises(InputError):
        fc.set_altitude_target(np.inf)
    with pytest.raises(InputError):
        fc.set_accel_reference((0.0, np.nan, 0.0))
    fc.set_accel_reference((0.5, 0.0, 0.0))
    fc.set_climb_rate(0.5)
    assert fc.inputs()["alt_mode"] == 1


def test_ground_truth_blend_is_continuous_in_the_core(stream):
    # The estimate says level; ground truth says rolled 0.2 rad: switching the
    # source moves the attitude error smoothly, with SB_BLEND_TC.
    q_gt = (np.cos(0.1), np.sin(0.1), 0.0, 0.0)
    fc = FlightCore()
    s = stream(gt=True)
    fc.step_batch(s.batch(500, q_gt=q_gt))
    fc.set_param("SB_ATT_SRC", 1)
    _, st = fc.step_batch(s.batch(1500, q_gt=q_gt))
    w = st["blend_w"]
    assert w[0] < 0.02 and w[-1] > 0.99
    ex = st["att_error_frd_rad"][:, 0]
    assert ex[-1] == pytest.approx(-0.2, abs=0.01)
    assert np.abs(np.diff(ex)).max() < 0.2 * 0.0025 / 0.25 * 1.2
    # with the blend feature off, the switch is a step
    fc2 = FlightCore()
    fc2.set_feature("blend", False)
    s2 = stream(gt=True)
    _, before = fc2.step_batch(s2.batch(500, q_gt=q_gt))
    fc2.set_param("SB_ATT_SRC", 1)
    _, after = fc2.step_batch(s2.batch(100, q_gt=q_gt))
    ex2 = np.concatenate([before["att_error_frd_rad"][:, 0], after["att_error_frd_rad"][:, 0]])
    assert np.abs(np.diff(ex2)).max() > 0.15


def test_stale_ground_truth_falls_back_to_the_estimate(stream):
    fc = FlightCore({"SB_ATT_SRC": 1})
    s = stream(gt=True)
    fc.step_batch(s.batch(1000))
    s.gt = False                          # truth stops arriving
    _, st = fc.step_batch(s.batch(2000))
    assert st["blend_w"][-1] < 0.01


def test_status_snapshot_and_reset(stream):
    fc = FlightCore()
    fc.step_batch(stream().batch(20))
    snap = fc.status()
    assert snap.dtype == STATUS_DTYPE and snap["sim_ns"] == 17_500_000
    fc.reset()
    assert fc.counters()["imu"] == 0
    assert fc.get_param("ATC_RAT_RLL_P") == pytest.approx(0.135)


def test_the_status_carries_the_control_laws_latest_step(stream):
    # fill_status copies the control law's report in one piece: each field must land in its
    # own status field. The batch ends on a PWM tick right after a rate-loop step, so the
    # status and the law's outputs (sysid_sample reads them directly) are the same step.
    fc = FlightCore()
    fc.arm()
    fc.set_attitude_target(0.1, -0.05)
    fc.step_batch(stream().batch(2001, gyro=(0.02, -0.01, 0.03)))   # IMU 0..2000 ms
    st, sample = fc.status(), fc.sysid_sample()
    assert st["sim_ns"] == sample[0] == 2_000_000_000
    np.testing.assert_array_equal(st["rate_target_frd_rad_s"], np.float32(sample[7:10]))
    np.testing.assert_array_equal(st["rate_frd_rad_s"], np.float32(sample[10:13]))
    pid_sum = st["pid_p"] + st["pid_i"] + st["pid_d"] + st["pid_ff"]
    np.testing.assert_allclose(pid_sum, np.float32(sample[13:16]), rtol=1e-6, atol=1e-6)
    assert np.all(st["pid_p"] != 0.0)
    # the shaped target has reached the command; the error is what the state lacks of it
    np.testing.assert_allclose(st["att_target_rad"][:2], [0.1, -0.05], atol=1e-3)
    assert st["att_error_frd_rad"][0] > 0.05 and st["att_error_frd_rad"][1] < -0.02


def test_gyro_bias_is_learned_on_the_ground_and_removed_from_the_rate_loop(stream):
    # Disarmed and still, the estimator runs its fast ground gains: a 0.05 rad/s
    # bias is learned within seconds, and the rate loop sees the corrected rate.
    fc = FlightCore()
    _, st = fc.step_batch(stream(mag_hz=0).batch(12_000, gyro=(0.05, -0.04, 0.0)))
    bias = st["gyro_bias_rad_s"]
    t_s = st["sim_ns"] / 1e9
    assert np.abs(bias[t_s > 10] - [0.05, -0.04, 0.0]).max() < 0.002
    assert np.abs(st["rate_frd_rad_s"][t_s > 10]).max() < 0.002
    assert np.abs(st["euler_est_rad"][t_s > 10, :2]).max() < np.radians(0.1)


def test_bound_batches_match_step_batch(stream):
    """FcLoop's path (bind_batch once, step_bound(n) per poll) gives step_batch's output."""
    recs = stream(gt=True).batch(2000)
    a, b = FlightCore(), FlightCore()
    for fc in (a, b):
        fc.arm()
    pa, sa = a.step_batch(recs)
    buf = np.zeros(512, R.RECORD_DTYPE)
    pwm_out = np.zeros(512, R.PWM_DTYPE)
    st_out = np.zeros(512, STATUS_DTYPE)
    b._c.bind_batch(buf, pwm_out, st_out)
    parts_p, parts_s = [], []
    for chunk in np.array_split(recs, [1, 7, 300, 301, 1000]):
        for i in range(0, len(chunk), 512):
            part = chunk[i:i + 512]
            buf[:len(part)] = part
            k = b._c.step_bound(len(part))
            parts_p.append(pwm_out[:k].copy())
            parts_s.append(st_out[:k].copy())
    pb, sb = np.concatenate(parts_p), np.concatenate(parts_s)
    assert sa.tobytes() == sb.tobytes()
    np.testing.assert_array_equal(pa["pwm_us"], pb["pwm_us"])


def test_step_bound_refuses_misuse():
    fc = FlightCore()
    with pytest.raises(RuntimeError, match="bind_batch"):
        fc._c.step_bound(1)
    buf = np.zeros(8, R.RECORD_DTYPE)
    fc._c.bind_batch(buf, np.zeros(4, R.PWM_DTYPE), np.zeros(4, STATUS_DTYPE))
    with pytest.raises(ValueError, match="holds 8"):
        fc._c.step_bound(9)
    with pytest.raises(ValueError, match="whole 64-byte"):
        fc._c.bind_batch(np.zeros(10, np.uint8), np.zeros(4, R.PWM_DTYPE),
                         np.zeros(4, STATUS_DTYPE))
