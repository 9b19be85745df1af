"""The vehicle's building blocks on their own: estimator, controllers, navigator, battery,
pilot input, parameter store (no simulator; fast)."""

from __future__ import annotations

import math
import threading

import pytest

from silbridge.fc_sil import params as P
from silbridge.fc_sil.battery import BatteryConfig, BatteryMonitor
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.nav_kinematics import sqrt_controller
from silbridge.fc_sil.nav_pos import PosController, PosGains, accel_to_lean
from silbridge.fc_sil.param_store import CoreParamStore
from silbridge.fc_sil.pilot import PilotInput
from silbridge.fc_sil.pos_est import GeoOrigin, PositionEstimator, quat_rotate_frd_to_ned

G = 9.80665


# ---- position estimator ------------------------------------------------------------------------

def test_geo_origin_round_trip_and_scale():
    o = GeoOrigin(473977420, 85455940, 488.0)
    lat, lon = o.to_latlon_e7(100.0, -50.0)
    n, e = o.to_ne(lat, lon)
    assert n == pytest.approx(100.0, abs=0.02) and e == pytest.approx(-50.0, abs=0.02)
    # one degree of latitude is ~111.3 km
    assert o.to_ne(o.lat_e7 + 10_000_000, o.lon_e7)[0] == pytest.approx(111_319.5, rel=1e-3)


def test_quat_rotation_of_gravity_reaction_when_pitched():
    # pitched nose-down by 10 deg, hovering: the specific force (-g along body z) tilts forward
    th = math.radians(-10.0)
    q = (math.cos(th / 2), 0.0, math.sin(th / 2), 0.0)
    f_ned = quat_rotate_frd_to_ned(q, (0.0, 0.0, -G / math.cos(th)))
    assert f_ned[0] == pytest.approx(G * math.tan(-th), rel=1e-6)   # accelerating north
    assert f_ned[2] == pytest.approx(-G, rel=1e-6)


def _fix(t_ns, o, n, e, vn=0.0, ve=0.0, fix_type=3):
    lat, lon = o.to_latlon_e7(n, e)
    return {"sim_ns": t_ns, "lat_e7": lat, "lon_e7": lon, "alt_mm": 488000,
            "vel_ned_m_s": (vn, ve, 0.0), "fix_type": fix_type, "satellites": 12}


def test_estimator_tracks_constant_acceleration_with_delayed_fixes():
    o = GeoOrigin(473977420, 85455940, 488.0)
    est = PositionEstimator(pos_tc_s=1.5, vel_tc_s=0.2, delay_s=0.11)
    a = 1.0                                  # m/s^2 north
    th = math.atan(a / G)
    q = (math.cos(-th / 2), 0.0, math.sin(-th / 2), 0.0)
    f_body = (0.0, 0.0, -math.hypot(a, G))
    dt_ns = 20_000_000
    assert not est.fuse_gnss(_fix(0, o, 0.0, 0.0, fix_type=1))      # no 3D fix: ignored
    t = 0
    for k in range(1, 501):                  # 10 s
        t = k * dt_ns
        est.predict(t, 0.02, q, f_body)
        if k % 5 == 0:                       # 10 Hz fixes describing the vehicle 110 ms ago
            tm = (t - 110_000_000) / 1e9
            est.fuse_gnss(_fix(t, o, 0.5 * a * tm * tm, 0.0, a * tm))
    ts = t / 1e9
    assert est.valid
    assert est.vel_ne_m_s[0] == pytest.approx(a * ts, abs=0.1)
    assert est.pos_ne_m[0] == pytest.approx(0.5 * a * ts * ts, abs=0.5)


def test_estimator_learns_an_accelerometer_bias():
    o = GeoOrigin(473977420, 85455940, 488.0)
    est = PositionEstimator(pos_tc_s=1.5, vel_tc_s=0.2, delay_s=0.0)
    q = (1.0, 0.0, 0.0, 0.0)
    f_body = (0.3, 0.0, -G)                  # 0.3 m/s^2 of bias while standing still
    for k in range(1, 3001):
        t = k * 20_000_000
        est.predict(t, 0.02, q, f_body)
        if k % 5 == 0:
            est.fuse_gnss(_fix(t, o, 0.0, 0.0))
    assert est.acc_bias_ne_m_s2[0] == pytest.approx(0.3, abs=0.05)
    assert abs(est.vel_ne_m_s[0]) < 0.05


def test_a_gnss_jump_past_the_retry_time_resets_the_estimate_and_reports_the_jump():
    # EKF3's getLastPosNorthEastReset: a count and the shift, for the position controllers
    o = GeoOrigin(473977420, 85455940, 488.0)
    est = PositionEstimator(pos_tc_s=1.5, vel_tc_s=0.2, delay_s=0.0)
    q, f_body = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, -G)
    seen = []
    for k in range(1, 1001):                 # 20 s standing still; fixes 30 m north from 5 s
        t = k * 20_000_000
        est.predict(t, 0.02, q, f_body)
        if k % 5 == 0:
            est.fuse_gnss(_fix(t, o, 30.0 if t >= 5_000_000_000 else 0.0, 0.0))
        seen.append((t, est.xy_reset_count))
    assert est.xy_reset_count == 1
    t_reset = next(t for t, c in seen if c == 1) / 1e9
    assert 15.0 <= t_reset <= 15.2           # 10 s of rejected positions (velocity passing)
    dn, de = est.xy_reset_ne_m
    assert dn == pytest.approx(30.0, abs=0.5) and de == pytest.approx(0.0, abs=0.1)
    assert est.xy_reset_vel_ne_m_s == (0.0, 0.0)      # the velocity still fused: no reset
    assert est.pos_ne_m[0] == pytest.approx(30.0, abs=0.1)


# ---- controllers ---------------------------------------------------------------------------------

def test_position_controller_follows_an_estimate_reset_without_a_jump_in_its_output():
    # AC_PosControl::handle_ekf_xy_reset: the target keeps its offset from the estimate
    def held(shift):
        pc = PosController(PosGains())
        pc.reset((0.0, 0.0), (0.0, 0.0))
        pos, out = [0.4, -0.3], None
        for _ in range(50):
            out = pc.update(0.02, pos, (0.2, 0.1))
        if shift:
            pc.shift((30.0, -2.0))
            pos = [pos[0] + 30.0, pos[1] - 2.0]
        target = pc.pos_target
        return target, pc.update(0.02, pos, (0.2, 0.1)), out

    (tn, te), after, before = held(False)
    (sn, se), after_shifted, _ = held(True)
    assert (sn, se) == (tn + 30.0, te - 2.0)
    assert after_shifted == pytest.approx(after, abs=1e-12)
    assert after == pytest.approx(before, abs=0.01)

def test_sqrt_controller_is_linear_near_zero_and_braking_curve_far():
    assert sqrt_controller(0.5, 1.0, 2.5) == pytest.approx(0.5)
    far = sqrt_controller(100.0, 1.0, 2.5)
    assert far == pytest.approx(math.sqrt(2 * 2.5 * (100.0 - 1.25)))
    assert sqrt_controller(-100.0, 1.0, 2.5) == pytest.approx(-far)


def test_accel_to_lean_signs_and_limit():
    roll, pitch = accel_to_lean(2.0, 0.0, 0.0, math.radians(30))    # go north, facing north
    assert pitch < 0 and abs(roll) < 1e-9                            # nose down
    roll, pitch = accel_to_lean(0.0, 2.0, 0.0, math.radians(30))    # go east: roll right
    assert roll > 0 and abs(pitch) < 1e-9
    roll, pitch = accel_to_lean(2.0, 0.0, math.pi / 2, math.radians(30))   # facing east
    assert roll < 0 and abs(pitch) < 1e-6                                   # roll left = north
    _, pitch = accel_to_lean(50.0, 0.0, 0.0, math.radians(30))
    assert pitch == pytest.approx(-math.radians(30))


def test_position_controller_velocity_command_is_shaped_by_accel_and_jerk():
    pc = PosController(PosGains(accel_m_s2=2.5, jerk_m_s3=5.0))
    pc.reset((0.0, 0.0), (0.0, 0.0))
    pc.input_vel_accel(0.02, (10.0, 0.0), (0.0, 0.0), 10.0)
    assert pc.accel_desired[0] == pytest.approx(5.0 * 0.02)      # jerk-limited first step
    for _ in range(500):
        pc.input_vel_accel(0.02, (10.0, 0.0), (0.0, 0.0), 10.0)
        assert abs(pc.accel_desired[0]) <= 2.5 + 1e-9
    assert pc.vel_desired[0] == pytest.approx(10.0, abs=0.01)
    # the position target moved along with the shaped velocity
    assert pc.pos_target[0] > 50.0


def test_a_reset_moves_guided_and_land_hold_points_and_the_controller_target_by_its_jump():
    # the vehicle follows each reset once (vehicle_nav.follow_xy_reset, every outer step)
    from silbridge.fc_sil import modes
    from silbridge.fc_sil.vehicle import Vehicle
    v = Vehicle(FlightCore())
    o = GeoOrigin(473977420, 85455940, 488.0)
    q, f_body = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, -G)
    held = {}
    for k in range(1, 1001):                 # fixes jump 30 m north at 5 s: a reset at 15 s
        t = k * 20_000_000
        v.est.predict(t, 0.02, q, f_body)
        if k % 5 == 0:
            v.est.fuse_gnss(_fix(t, o, 30.0 if t >= 5_000_000_000 else 0.0, 2.0))
        if k == 200:                         # 4 s: hold here (a take-off's hold point)
            g = modes.Guided()
            g.enter(v)
            g.start_takeoff(v, 10.0)
            v.mode = g
            v.pos_ctl.reset(v.est.pos_ne_m, (0.0, 0.0))
            held = {"hold": g.hold_ne, "target": v.pos_ctl.pos_target, "shape": g.pos_d}
        v.follow_xy_reset()
    dn, de = v.est.xy_reset_ne_m
    assert v.est.xy_reset_count == 1 and dn == pytest.approx(30.0, abs=0.5)
    for name, now in (("hold", v.mode.hold_ne), ("target", v.pos_ctl.pos_target),
                      ("shape", v.mode.pos_d)):
        assert now == pytest.approx((held[name][0] + dn, held[name][1] + de), abs=1e-9), name
    land = modes.Land()
    land.hold_ne = (1.0, 2.0)
    v.mode = land
    v.est.xy_reset_count += 1               # a second reset with the same jump
    v.follow_xy_reset()
    v.follow_xy_reset()                      # followed once only
    assert land.hold_ne == pytest.approx((1.0 + dn, 2.0 + de), abs=1e-9)


# ---- battery and pilot ---------------------------------------------------------------------------

def test_battery_monitor_reads_the_bridges_pack_through_the_core():
    """The FC's battery is the bridge's BATTERY record, kept by the C record router."""
    from silbridge.shm.records import Kind, empty
    core = FlightCore()
    b = BatteryMonitor(BatteryConfig(capacity_mah=3000.0))
    b.read(core)
    assert not b.valid and b.remaining_pct == -1 and b.current_a == -1.0
    rec = empty(Kind.BATTERY, 1)
    rec["sim_ns"] = 100_000_000
    rec["voltage_v"], rec["current_a"], rec["consumed_mah"] = 15.5, 12.25, 321.0
    rec["remaining"], rec["temperature_c"], rec["lowest_cell_v"], rec["cell_count"] = 0.5, 31.5, 3.75, 4
    core.step_batch(rec)
    b.read(core)
    assert b.valid and b.sim_ns == 100_000_000
    assert (b.voltage_v, b.current_a, b.consumed_mah) == (15.5, 12.25, 321.0)
    assert (b.temperature_c, b.lowest_cell_v, b.cells) == (31.5, 3.75, 4)
    assert b.remaining_pct == 50 and b.remaining_mah == 1500.0     # the pack's charge x BATT_CAPACITY


def test_pilot_sticks_from_manual_control_and_rc_override():
    p = PilotInput(clock=lambda: 100.0)
    assert p.age_s() is None and not p.fresh(1.0)
    p.manual_control(1000, -500, 250, 32767)         # full forward, half left, yaw unused
    assert (p.pitch, p.roll, p.throttle, p.yaw) == (-1.0, -0.5, 0.25, 0.0)
    p.rc_override((1500, 1000, 2000, 1750) + (0,) * 14)
    assert (p.roll, p.pitch, p.throttle, p.yaw) == (0.0, -1.0, 1.0, 0.5)
    p.rc_override((65535, 0, 1000, 65535) + (0,) * 14)   # 0/65535 keep the channel
    assert (p.roll, p.pitch, p.throttle, p.yaw) == (0.0, -1.0, 0.0, 0.5)
    assert p.fresh(1.0)


# ---- parameter store -----------------------------------------------------------------------------

def test_param_store_lists_every_declared_parameter_with_its_type():
    store = CoreParamStore(FlightCore())
    assert list(store.names()) == [p.name for p in P.PARAMS]
    assert store.get("DISARM_DELAY") == (10, 2)          # INT8, reported as an integer
    v, t = store.get("ATC_RAT_RLL_P")
    assert t == 9 and v == pytest.approx(0.135)
    with pytest.raises(KeyError):
        store.get("NOT_A_PARAM")


def test_param_store_echoes_at_once_and_applies_at_the_step_boundary():
    core = FlightCore()
    store = CoreParamStore(core)
    assert store.set("ATC_RAT_RLL_P", 0.2) is None
    assert store.get("ATC_RAT_RLL_P")[0] == pytest.approx(0.2)      # echo
    assert core.get_param("ATC_RAT_RLL_P") == pytest.approx(0.135)   # not yet live
    assert store.apply() == 1
    assert core.get_param("ATC_RAT_RLL_P") == pytest.approx(0.2)
    assert store.set("WPNAV_SPEED", 500) is None
    store.apply()
    assert core.get_param("WPNAV_SPEED") == 500


def test_param_store_refuses_what_the_core_would_refuse():
    core = FlightCore()
    store = CoreParamStore(core)
    assert "outside" in store.set("ATC_RAT_RLL_P", 5.0)
    assert store.set("MOT_PWM_MIN", 1950) is not None        # MIN + 100 <= MAX
    assert store.get("MOT_PWM_MIN")[0] == 1000
    assert "integer" in store.set("DISARM_DELAY", 2.5)
    assert store.apply() == 0
    assert store.sets_refused == 3


def test_param_store_set_from_another_thread_while_the_loop_steps():
    import numpy as np

    from silbridge.shm.records import Kind, empty
    core = FlightCore()
    store = CoreParamStore(core)
    recs = empty(Kind.IMU, 64)
    recs["sim_ns"] = np.arange(64) * 1_000_000
    recs["accel_frd_m_s2"] = (0.0, 0.0, -G)
    stop = threading.Event()

    def gcs():
        k = 0
        while not stop.is_set():
            store.set("ATC_RAT_RLL_D", 0.001 * (k % 10))
            k += 1

    th = threading.Thread(target=gcs)
    th.start()
    try:
        for i in range(300):
            r = recs.copy()
            r["sim_ns"] += i * 64_000_000
            core.step_batch(r.view(np.dtype((np.void, 64))))
            store.apply()
    finally:
        stop.set()
        th.join()
    store.apply()
    assert core.get_param("ATC_RAT_RLL_D") == pytest.approx(store.get("ATC_RAT_RLL_D")[0])
