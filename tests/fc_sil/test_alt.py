"""fc_alt_est.c + fc_alt_ctrl.c + the spool logic of fc_spool.c: the vertical channel.

The FC flies a level vertical point mass (four motors with a first-order lag,
thrust linear in PWM) in closed loop, one IMU record per millisecond and a
barometer at 100 Hz, through FlightCore.step_batch. The plant's hover throttle
deliberately differs from MOT_THST_HOVER, so the accel integrator must learn it.
Altitude and climb are positive up (NED down negated).
"""

import numpy as np
import pytest

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.status import SPOOL_FLIGHT, SPOOL_GROUND_IDLE
from silbridge.shm import records as R

G = 9.80665


class VerticalPlant:
    def __init__(self, hover_throttle=0.42, mass_kg=1.5):
        self.m = mass_kg
        self.t_max = mass_kg * G / (4 * hover_throttle)   # per motor [N]
        self.h = 0.0
        self.v = 0.0
        self.u = np.zeros(4)
        self.specific_force_z = -G
        self.baro_offset_m = 0.0        # the baro reads this much higher (a baro fault)

    def step(self, pwm_us, dt):
        cmd = np.clip((np.asarray(pwm_us[:4], float) - 1000.0) / 1000.0, 0.0, 1.0)
        self.u += (cmd - self.u) * dt / 0.03
        thrust = self.t_max * self.u.sum()
        a = thrust / self.m - G
        if self.h <= 0.0 and a <= 0.0:       # on the ground: the ground holds it
            self.v = 0.0
            self.specific_force_z = -G
            return
        self.specific_force_z = -thrust / self.m
        self.v += a * dt
        self.h = max(0.0, self.h + self.v * dt)


def fly(fc, plant, seconds, t0_ms=0, on_tick=None):
    rows = []
    pwm_now = (1000, 1000, 1000, 1000)
    rng = np.random.default_rng(1)
    for k in range(t0_ms, t0_ms + int(seconds * 1000)):
        imu = R.empty(R.Kind.IMU, 1)
        imu["sim_ns"] = k * 1_000_000
        imu["seq"] = k
        imu["accel_frd_m_s2"] = (0.0, 0.0, plant.specific_force_z)
        recs = [R.as_generic(imu)]
        if k % 10 == 0:
            b = R.empty(R.Kind.BARO, 1)
            b["sim_ns"] = k * 1_000_000
            b["pressure_pa"] = 101325.0 * (1 - 2.25577e-5 * (plant.h + plant.baro_offset_m)) \
                ** 5.25588 \
                + rng.normal(0, 0.5)
            recs.append(R.as_generic(b))
        pwm, st = fc.step_batch(np.concatenate(recs))
        if len(pwm):
            pwm_now = tuple(pwm["pwm_us"][-1][:4])
            rows.append((st[-1].copy(), plant.h, plant.v))
        plant.step(pwm_now, 0.001)
    status = np.array([r[0] for r in rows])
    return status, np.array([r[1] for r in rows]), np.array([r[2] for r in rows])


@pytest.fixture(scope="module")
def takeoff():
    fc = FlightCore()
    plant = VerticalPlant()
    fly(fc, plant, 1.0)                 # disarmed: the baro reference settles
    fc.arm()
    fc.set_altitude_target(5.0)
    st, h, v = fly(fc, plant, 14.0, t0_ms=1000)
    return fc, plant, st, h, v


def test_takes_off_and_holds_the_altitude_target(takeoff):
    fc, plant, st, h, v = takeoff
    assert h[-1] == pytest.approx(5.0, abs=0.3)
    assert st["alt_est_m"][-1] == pytest.approx(h[-1], abs=0.3)
    assert np.all(st["spool"][-100:] == SPOOL_FLIGHT)


def test_climb_rate_is_limited_by_pilot_speed_up(takeoff):
    _, _, st, h, v = takeoff
    assert v.max() < 2.5 * 1.15                       # PILOT_SPEED_UP 250 cm/s
    assert st["climb_target_m_s"].max() == pytest.approx(2.5, abs=1e-4)


def test_estimator_signs_are_up_positive(takeoff):
    _, _, st, h, v = takeoff
    climbing = v > 1.0
    assert climbing.any()
    assert np.all(st["climb_est_m_s"][climbing] > 0.3)
    assert st["alt_est_m"][-1] > 0


def test_liftoff_detected_above_sb_liftoff_alt(takeoff):
    fc, _, st, h, v = takeoff
    first_air = np.argmax(st["airborne"] == 1)
    assert st["airborne"][first_air] == 1
    assert st["alt_est_m"][first_air] >= fc.get_param("SB_LIFTOFF_ALT") - 1e-6
    assert np.all(st["airborne"][first_air:] == 1)
    assert np.all(st["pid_i"][:first_air] == 0)       # no rate-loop wind-up on the ground


def test_accel_integrator_learns_the_hover_throttle(takeoff):
    _, _, st, _, _ = takeoff
    assert st["throttle"][-200:].mean() == pytest.approx(0.42, abs=0.02)


def test_descends_lands_and_returns_to_ground_idle():
    fc = FlightCore()
    plant = VerticalPlant(hover_throttle=0.35)
    fc.arm()
    fc.set_altitude_target(2.0)
    fly(fc, plant, 6.0)
    fc.set_altitude_target(0.0)
    st, h, v = fly(fc, plant, 8.0, t0_ms=6000)
    assert h[-1] == pytest.approx(0.0, abs=1e-6)
    assert st["spool"][-1] == SPOOL_GROUND_IDLE and st["airborne"][-1] == 0
    assert v.min() > -(2.5 * 1.15)                    # PILOT_SPEED_DN 0 = PILOT_SPEED_UP


def test_climb_rate_and_direct_throttle_modes():
    fc = FlightCore()
    plant = VerticalPlant(hover_throttle=0.35)
    fc.arm()
    fc.set_climb_rate(1.0)
    st, h, v = fly(fc, plant, 5.0)
    assert v[-400:].mean() == pytest.approx(1.0, abs=0.1)
    assert st["climb_est_m_s"][-1] == pytest.approx(1.0, abs=0.15)
    fc.set_throttle(0.35)                              # the plant's hover throttle
    st, h, v = fly(fc, plant, 3.0, t0_ms=5000)
    assert st["throttle_us"][-1] == pytest.approx(1350, abs=1)
    assert abs(v[-1]) < 1.1                             # no longer driven up


def test_landing_slews_down_to_idle_without_a_dip():
    fc = FlightCore()
    plant = VerticalPlant(hover_throttle=0.35)
    fc.arm()
    fc.set_altitude_target(1.0)
    fly(fc, plant, 4.0)
    fc.set_altitude_target(0.0)
    st, h, v = fly(fc, plant, 6.0, t0_ms=4000)
    landed = np.argmax(st["spool"] == SPOOL_GROUND_IDLE)
    assert landed > 0
    assert st["pwm_us"][landed - 1:, :4].min() >= 1100          # never below MOT_SPIN_ARM
    assert np.all(st["pwm_us"][-1, :4] == 1100)


def test_vertical_accel_bias_is_learned_on_the_ground():
    fc = FlightCore()

    def still(fc, seconds, t0_ms):
        rows = []
        for k in range(t0_ms, t0_ms + int(seconds * 1000)):
            imu = R.empty(R.Kind.IMU, 1)
            imu["sim_ns"] = k * 1_000_000
            imu["accel_frd_m_s2"] = (0.0, 0.0, -G - 0.4)   # a 0.4 m/s^2 offset, at rest
            recs = [R.as_generic(imu)]
            if k % 10 == 0:
                b = R.empty(R.Kind.BARO, 1)
                b["sim_ns"] = k * 1_000_000
                b["pressure_pa"] = 101325.0
                recs.append(R.as_generic(b))
            _, st = fc.step_batch(np.concatenate(recs))
            rows.extend(st)
        return np.array(rows)

    still(fc, 5.0, 0)                          # disarmed: bias learned
    fc.arm()
    st = still(fc, 2.0, 5000)                  # armed on the ground: no drift
    assert np.abs(st["alt_est_m"]).max() < 0.02
    assert np.abs(st["climb_est_m_s"]).max() < 0.02
