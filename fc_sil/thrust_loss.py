"""Thrust-loss check: ArduCopter 4.6's thrust_loss_check (ArduCopter/crash_check.cpp).

While armed and flying (FLIGHT_OPTIONS bit 0 clear), a motor has probably lost thrust when,
for 1 s of sim time at once: the attitude target leans less than 15 deg, the altitude loop asks
for at least 90 % throttle (or the mixer clips throttle high) and at least 25 %, the vehicle
descends, and the thrust vector is within 30 deg of the target (attitude control holds).
Then "Potential Thrust Loss (N)" (EMERGENCY), N the motor whose output, low-passed with a
0.5 s time constant, is the highest: the one the mixer drives hardest to make up for its lost
thrust (AP_MotorsMatrix::check_for_failed_motor). Motors are numbered in our mixer's output
order, ArduCopter's QUAD X (fc_mixer.h).

ArduCopter then sets the motors' thrust boost, which lets throttle use the full range and, on
frames of six or more motors only, stops demanding from the failed motor. Our quad mixer
always has the full range and a quad cannot drop a motor, so the boost changes nothing here:
``boost`` is kept as ArduCopter's flag (no second warning while on) and clears when no motor
is driven above 90 % and the altitude loop's demand fits below 90 % again.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.status import SAT_THR_HIGH

from silbridge.shm.records import NS_PER_S as NS

from .crash_check import ANGLE_DEVIATION_DEG, thrust_error_deg
from .held_for import HeldFor

TRIGGER_S = 1.0                 # THRUST_LOSS_CHECK_TRIGGER_SEC
ANGLE_DEVIATION_DEG_TGT = 15.0  # THRUST_LOSS_CHECK_ANGLE_DEVIATION_CD / 100
MINIMUM_THROTTLE = 0.9          # THRUST_LOSS_CHECK_MINIMUM_THROTTLE
LOW_THROTTLE = 0.25             # below this the limit is the command, not the motors
MOTOR_FILT_TC_S = 0.5           # AP_MotorsMatrix: alpha = 1 / (1 + loop_rate * 0.5)
BOOST_CLEAR_OUT = 0.9           # boost ends when the highest motor output is below this
OPT_DISABLE_THRUST_LOSS = 1     # FLIGHT_OPTIONS bit 0


class ThrustLossCheck:
    def __init__(self, motors: int = 4):
        self.out_filt = [0.0] * motors
        self.boost = False
        self.lost_motor = 0             # 0-based, held while boost is on
        self._held = HeldFor(TRIGGER_S)
        self._last_ns = None

    def _track_motors(self, v) -> None:
        st = v.status
        dt = 0.0 if self._last_ns is None else (v.sim_ns - self._last_ns) / NS
        self._last_ns = v.sim_ns
        if st is None or not v.armed:
            self.out_filt = [0.0] * len(self.out_filt)
            return
        span = max(1.0, v.cfg.pwm_max_us - v.cfg.pwm_min_us)
        alpha = dt / (dt + MOTOR_FILT_TC_S)
        for i, pwm in enumerate(st["pwm_us"][:len(self.out_filt)]):
            out = (float(pwm) - v.cfg.pwm_min_us) / span
            self.out_filt[i] += alpha * (out - self.out_filt[i])
        high = max(range(len(self.out_filt)), key=lambda i: self.out_filt[i])
        if not self.boost:
            self.lost_motor = high
        elif (self.out_filt[high] < BOOST_CLEAR_OUT and float(st["throttle"]) < MINIMUM_THROTTLE
              and not int(st["sat_flags"]) & SAT_THR_HIGH):
            self.boost = False      # the demand fits under full throttle again

    def check(self, v) -> None:
        self._track_motors(v)
        if int(v.store.host("FLIGHT_OPTIONS")) & OPT_DISABLE_THRUST_LOSS or self.boost:
            return
        st = v.status
        suspect = v.armed and v.airborne and st is not None and self._suspect(v, st)
        if self._held.update(suspect, v.sim_ns):
            self.boost = True
            v.statustext(mav.MAV_SEVERITY_EMERGENCY,
                         f"Potential Thrust Loss ({self.lost_motor + 1})")

    @staticmethod
    def _suspect(v, st) -> bool:
        tgt = tuple(float(x) for x in st["att_target_rad"])
        if math.hypot(tgt[0], tgt[1]) > math.radians(ANGLE_DEVIATION_DEG_TGT):
            return False
        thr = float(st["throttle"])
        if thr < MINIMUM_THROTTLE and not int(st["sat_flags"]) & SAT_THR_HIGH:
            return False
        if thr < LOW_THROTTLE or v.climb_m_s >= 0.0:
            return False
        return thrust_error_deg(tgt, v.euler_rad) < ANGLE_DEVIATION_DEG
