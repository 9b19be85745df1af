"""GNSS-aided tilt correction (fc_gnss_aid.c, fc_mahony_gnss) through the real FlightCore.

A synthetic multirotor: the attitude follows a given roll/pitch profile (yaw 0), the thrust
holds the altitude (|f| = g / cos(tilt) along body -z, so the accelerometer "looks level" and
the vehicle accelerates horizontally at g tan(tilt)), the gyro reads the true body rate plus
an optional bias, the magnetometer the rotated Earth field, and GNSS the true velocity at
10 Hz epochs, delivered 110 ms late (as bridge/lowrate.py models a receiver). The records go
through FlightCore.step_batch as the shared-memory ring delivers them.
"""

import numpy as np
import pytest

import fc_blocks as B
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import records as R

G = 9.80665
IMU_HZ = 1000
GNSS_HZ = 10
LATENCY_NS = 110_000_000
FIELD_NED = np.array([0.2136, 0.0, 0.4312])  # declination 0: COMPASS_DEC default


def quat_from_euler(roll, pitch, yaw):
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy], axis=-1)


def rot(q):
    """Body FRD -> NED rotation matrices of quaternions (n, 4) -> (n, 3, 3)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], axis=-2)


def tilt_deg(q_est, q_true):
    """Angle between the 'down' directions of two attitude sets [deg]."""
    d1, d2 = rot(q_est)[:, 2, :], rot(q_true)[:, 2, :]
    return np.degrees(np.arccos(np.clip(np.sum(d1 * d2, axis=1), -1.0, 1.0)))


def flight(roll_rad, pitch_rad, *, gyro_bias=None, field_ned=FIELD_NED, t_end_s=None):
    """Records of a synthetic flight; roll/pitch: functions of t [s] -> rad (arrays).
    Returns (records, t_imu_s, q_true) with q_true per IMU sample."""
    n = int(round((t_end_s or T_END_S) * IMU_HZ))
    t_ns = (np.arange(1, n + 1) * (1_000_000_000 // IMU_HZ)).astype(np.int64)
    t = t_ns * 1e-9
    roll, pitch = roll_rad(t), pitch_rad(t)
    q = quat_from_euler(roll, pitch, np.zeros_like(t))
    r = rot(q)
    # Body rates of a yaw-0 Euler profile: p = roll' - sin(pitch) yaw', q = cos(roll) pitch'...
    droll, dpitch = np.gradient(roll, t), np.gradient(pitch, t)
    gyro = np.stack([droll, np.cos(roll) * dpitch, -np.sin(roll) * dpitch], axis=1)
    if gyro_bias is not None:
        gyro = gyro + gyro_bias(t)
    thrust = G / (np.cos(roll) * np.cos(pitch))
    f_frd = np.zeros((n, 3))
    f_frd[:, 2] = -thrust
    f_ned = np.einsum("nij,nj->ni", r, f_frd)
    a_ned = f_ned + [0.0, 0.0, G]
    vel = np.cumsum(a_ned, axis=0) / IMU_HZ

    imu = R.empty(R.Kind.IMU, n)
    imu["sim_ns"], imu["seq"] = t_ns, np.arange(n)
    imu["accel_frd_m_s2"], imu["gyro_frd_rad_s"] = f_frd, gyro
    mag_idx = np.arange(9, n, IMU_HZ // 100)
    mag = R.empty(R.Kind.MAG, len(mag_idx))
    mag["sim_ns"], mag["seq"] = t_ns[mag_idx], np.arange(len(mag_idx))
    mag["field_frd_gauss"] = np.einsum("nji,j->ni", r[mag_idx], field_ned)
    epochs = np.arange(IMU_HZ // GNSS_HZ - 1, n, IMU_HZ // GNSS_HZ)
    epochs = epochs[t_ns[epochs] + LATENCY_NS <= t_ns[-1]]
    gnss = R.empty(R.Kind.GNSS, len(epochs))
    gnss["sim_ns"], gnss["seq"] = t_ns[epochs] + LATENCY_NS, np.arange(len(epochs))
    gnss["vel_ned_m_s"] = vel[epochs]
    gnss["fix_type"], gnss["satellites"] = 3, 14
    recs = np.concatenate([R.as_generic(imu), R.as_generic(mag), R.as_generic(gnss)])
    # Time order; at equal times the IMU sample first, as the bridge publishes a step.
    order = np.lexsort((recs["kind"] != int(R.Kind.IMU), recs["sim_ns"]))
    return recs[order], t, q


T_END_S = 20.0
TILT_START_S = 4.0   # disarmed, level and still until here: ground alignment


def held_tilt(deg, start_s=TILT_START_S, ramp_s=0.5):
    def f(t):
        return np.radians(deg) * np.clip((t - start_s) / ramp_s, 0.0, 1.0)
    return f


def zero(t):
    return np.zeros_like(t)


def doublets(deg, start_s=TILT_START_S, delay_s=0.0):
    """Doublets every 5 s: 0.3 s ramp to +deg, 1.5 s hold, 0.6 s to -deg, hold, level."""
    def f(t):
        knots_t = np.array([0.0, 0.3, 1.8, 2.4, 3.9, 4.2, 5.0])
        knots_v = np.radians([0.0, deg, deg, -deg, -deg, 0.0, 0.0])
        v = np.interp(np.mod(t - start_s - delay_s, 5.0), knots_t, knots_v)
        return np.where(t >= start_s + delay_s, v, 0.0)
    return f


def fly(records, t, q_true, params=None):
    """Feed the records in 0.5 s batches, arming at 2 s; estimate error per status row."""
    fc = FlightCore(params or {})
    rows = []
    edges = np.searchsorted(records["sim_ns"], np.arange(0, t[-1] + 0.5, 0.5) * 1e9)
    for a, b in zip(edges[:-1], edges[1:]):
        if records["sim_ns"][a] >= 2e9 and not fc.armed:
            fc.arm()
        _, st = fc.step_batch(records[a:b])
        rows.append(st.copy())
    st = np.concatenate(rows)
    t_st = st["sim_ns"] * 1e-9
    idx = np.clip(np.searchsorted(t, t_st + 1e-12, side="right") - 1, 0, len(t) - 1)
    return fc, t_st, tilt_deg(st["q_est_wxyz"].astype(float), q_true[idx]), st


@pytest.mark.parametrize("deg", [20.0, 30.0])
def test_held_tilt_with_gnss_aiding_keeps_the_estimate_on_truth(deg):
    # 20-30 deg held for 15 s: the vehicle accelerates sideways at g tan(tilt) and the
    # accelerometer sees thrust only. Unaided, the estimate sinks towards "level"; with
    # GNSS velocity (110 ms late, delay known as GPS_DELAY_MS) it stays within ~1 deg.
    recs, t, q = flight(held_tilt(deg), zero)
    fc, t_st, err, _ = fly(recs, t, q)
    held = t_st > TILT_START_S + 1.0
    assert err[held].max() < 1.5
    assert np.sqrt(np.mean(err[held] ** 2)) < 0.8
    assert fc.counters()["gnss_aid"] > 100 and fc.counters()["gnss_aid_active"]

    _, t_st, err_off, _ = fly(recs, t, q, {"SB_AHRS_GPS": 0})
    assert err_off[t_st > T_END_S - 2.0].min() > 0.3 * deg   # what the aiding fixes


def _bias_step(t):
    """0.04 rad/s onto the roll and pitch gyros at 8 s (yaw is the magnetometer's)."""
    return np.where(t >= 8.0, 0.04, 0.0)[:, None] * [1.0, 1.0, 0.0]


def test_a_gyro_bias_step_in_flight_is_learned_from_the_aided_tilt_error():
    # Roll doublets of 20 deg (the accelerometer sees the thrust axis only) and a gyro
    # bias step at 8 s, as S2 injects it in flight. The GNSS-aided integrator learns it:
    # the tilt error peaks near 2.5 deg and is back under 1 deg within seconds; what is
    # left decays with the magnetometer's slow heading integrator (rolled, the pitch-gyro
    # bias partly turns the heading, and a heading error tilts the aided reference).
    recs, t, q = flight(doublets(20.0), zero, gyro_bias=_bias_step)
    _, t_st, err, st = fly(recs, t, q)
    assert err[t_st > 8.0].max() < 3.0
    assert err[t_st > 16.0].max() < 1.0
    assert np.sqrt(np.mean(err[t_st > 16.0] ** 2)) < 0.6
    # The rate loop removes the estimator's whole bias estimate (bias - integrator): in
    # the last hold (19.4-20 s, doublet phase 0.4-1.0 s) the body does not rotate.
    fc_rate = st["rate_frd_rad_s"][t_st > 19.4, :2]
    assert np.abs(fc_rate.mean(axis=0)).max() < 0.1 * 0.04


def test_unaided_estimate_loses_the_tilt_in_the_same_bias_step():
    # The same flight with the aiding off: no tilt reference in flight, so the bias
    # cannot be told from the thrust axis and the tilt error grows far beyond.
    recs, t, q = flight(doublets(20.0), zero, gyro_bias=_bias_step)
    _, t_st, err, _ = fly(recs, t, q, {"SB_AHRS_GPS": 0})
    assert err[t_st > 16.0].max() > 6.0


def test_a_wrong_declination_is_learned_from_gnss_while_manoeuvring():
    # The Earth field is 5 deg east of true north but COMPASS_DEC says 0: the heading
    # follows magnetic north, and under acceleration that tilts the GNSS reference. Roll
    # and pitch doublets make the heading error observable; the learned offset converges
    # on the declination and the tilt error shrinks with it.
    dec = np.radians(5.0)
    field = np.array([0.24 * np.cos(dec), 0.24 * np.sin(dec), 0.43])
    roll, pitch = doublets(25.0), doublets(25.0, delay_s=2.5)
    recs, t, q = flight(roll, pitch, field_ned=field, t_end_s=70.0)
    fc, t_st, err, _ = fly(recs, t, q)
    assert np.degrees(fc.counters()["heading_offset_rad"]) == pytest.approx(5.0, abs=1.0)
    late = t_st > 50.0
    fc_known, _, err_known, _ = fly(recs, t, q, {"COMPASS_DEC": float(dec)})
    assert abs(fc_known.counters()["heading_offset_rad"]) < np.radians(1.0)
    assert np.sqrt(np.mean(err[late] ** 2)) < 0.3 + np.sqrt(np.mean(err_known[late] ** 2))
    early = (t_st > TILT_START_S + 2.0) & (t_st < 14.0)
    assert err[early].max() > 1.5 * err[late].max()   # it did start wrong


def test_receiver_delay_is_taken_into_account():
    # Roll doublets of 25 deg: the acceleration changes fast, so comparing a fix with the
    # IMU over the wrong interval (GPS_DELAY_MS = 0 while the receiver is 110 ms late)
    # corrupts the tilt; with the right delay it stays on truth.
    recs, t, q = flight(doublets(25.0), zero)
    _, t_st, err_ok, _ = fly(recs, t, q)
    _, _, err_bad, _ = fly(recs, t, q, {"GPS_DELAY_MS": 0})
    flying = t_st > TILT_START_S + 2.0
    rms_ok = np.sqrt(np.mean(err_ok[flying] ** 2))
    rms_bad = np.sqrt(np.mean(err_bad[flying] ** 2))
    assert rms_ok < 0.3
    assert rms_bad > 3.0 * rms_ok


def test_no_aiding_while_disarmed_or_without_a_3d_fix():
    recs, t, q = flight(zero, zero)
    fc = FlightCore()
    fc.step_batch(recs)
    assert fc.counters()["gnss_aid"] == 0        # disarmed: ground alignment only
    recs2 = recs.copy()
    gn = recs2["kind"] == int(R.Kind.GNSS)
    g = recs2[gn].view(R.GNSS_DTYPE)
    g["fix_type"] = 2
    recs2[gn] = g.view(R.RECORD_DTYPE)
    fc = FlightCore()
    fc.arm()
    fc.step_batch(recs2)
    assert fc.counters()["gnss_aid"] == 0


def test_mahony_gnss_refuses_directionless_or_opposite_forces():
    m = B.Mahony()
    assert m.gnss((0.0, 0.0, -G), (0.0, 0.0, -G)) == 0
    assert m.state()["gnss_active"]
    assert m.gnss((0.0, 0.0, -1.0), (0.0, 0.0, -G)) != 0     # near free fall
    assert m.gnss((0.0, 0.0, G), (0.0, 0.0, -G)) != 0        # opposite: a glitch
    assert m.gnss((0.0, float("nan"), -G), (0.0, 0.0, -G)) != 0


def test_mahony_gnss_error_corrects_towards_the_gnss_direction():
    # The estimate is level; GNSS says the specific force leans 5 deg towards east
    # (the vehicle is rolled 5 deg right, accelerating east at g tan 5 deg... here only
    # the direction matters). Fed every 0.1 s, the estimate rolls to 5 deg.
    m = B.Mahony()
    dt = 0.001
    for _ in range(100):
        q = np.array(m.state()["q_wxyz"])
        # the accelerometer: thrust along body -z, so f_imu (rotated by the estimate)
        # is the estimate's "up"; the truth is a 5 deg roll
        f_imu = rot(q[None])[0] @ np.array([0.0, 0.0, -G / np.cos(np.radians(5))])
        true_q = quat_from_euler(np.radians(5), 0.0, 0.0)
        f_true = rot(true_q[None])[0] @ np.array([0.0, 0.0, -G / np.cos(np.radians(5))])
        assert m.gnss(f_imu, f_true) == 0
        acc = np.tile([0.0, 0.0, -G / np.cos(np.radians(5))], (100, 1))
        m.run(np.zeros((100, 3)), acc, dt)
    q = np.array(m.state()["q_wxyz"])
    roll = np.degrees(np.arctan2(2 * (q[0] * q[1] + q[2] * q[3]), 1 - 2 * (q[1] ** 2 + q[2] ** 2)))
    assert roll == pytest.approx(5.0, abs=0.3)
