"""EKF failsafe: ArduCopter 4.6's ekf_check (ArduCopter/ekf_check.cpp) on our test ratios.

Run at 10 Hz of sim time once the estimator has an origin. Each run is a pass or a fail:

* over threshold: the position and velocity ratios are low-passed at FS_EKF_FILT; with
  T = FS_EKF_THRESH, two of {compass >= T, velocity >= T} count, velocity >= 2T counts twice,
  and a fail needs two counts, or position >= T with one;
* no position: the estimator has no absolute horizontal position (GNSS timed out).

A fail adds one to a counter and a pass takes one off. The counter reaching 10 (1 s)
declares bad variance: "EKF variance" (at most every 30 s) and the failsafe event; it
clears when the counter is back at 0 ("EKF Failsafe Cleared" if an action was taken).
Nothing counts until the checks have passed once (a vehicle that boots without GNSS is not
in failsafe). FS_EKF_THRESH 0 turns the check off and clears it.

The event acts only when armed and in a mode that needs position (or FS_EKF_ACTION 3):
FS_EKF_ACTION 1 LAND, 2 ALT_HOLD (LAND if the radio failsafe is on), 3 LAND even from
STABILIZE; then "EKF Failsafe: changed to <MODE> Mode". In LAND it only stops LAND using
position, which our LAND does by itself once the vehicle has no position
(Vehicle.position_ok is false while this failsafe is on, as Copter::position_ok).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode

NS = 1_000_000_000
PERIOD_NS = NS // 10            # ekf_check runs at 10 Hz
ITERATIONS_MAX = 10             # EKF_CHECK_ITERATIONS_MAX: 1 s of fails
WARNING_TIME_S = 30.0           # EKF_CHECK_WARNING_TIME
ACTION_LAND, ACTION_ALTHOLD, ACTION_LAND_EVEN_STABILIZE = 1, 2, 3


class LowPass:
    """First-order low-pass with a cutoff in Hz (ArduPilot's LowPassFilterFloat); 0 = off."""

    def __init__(self):
        self.value = 0.0

    def apply(self, x: float, dt_s: float, cutoff_hz: float) -> float:
        if cutoff_hz <= 0 or dt_s <= 0:
            self.value = x
        else:
            rc = 1.0 / (2.0 * math.pi * cutoff_hz)
            self.value += (x - self.value) * dt_s / (dt_s + rc)
        return self.value


class EkfCheck:
    def __init__(self):
        self.fail_count = 0
        self.bad_variance = False
        self.failsafe = False           # Copter failsafe.ekf
        self.acted = False              # AP_Notify failsafe_ekf: an action was taken
        self.has_ever_passed = False
        self.pos_filt = LowPass()       # shared with the vibration check, as ArduCopter's
        self.vel_filt = LowPass()
        self._next_ns = 0
        self._last_ns = None
        self._last_warn_ns = None

    def check(self, v, ratios) -> None:
        if v.sim_ns < self._next_ns:
            return
        self._next_ns = v.sim_ns - v.sim_ns % PERIOD_NS + PERIOD_NS
        if v.est.origin is None:
            return
        get = v.store.host
        thresh = get("FS_EKF_THRESH")
        over = self._over_threshold(v, ratios, thresh, get("FS_EKF_FILT"))
        if thresh <= 0:
            self.fail_count = 0
            self.bad_variance = False
            self._off_event(v)
            return
        passed = not over and v.est.has_position(v.sim_ns)
        self.has_ever_passed |= passed
        if not self.has_ever_passed:
            return
        if not passed:
            if not self.bad_variance:
                self.fail_count += 1
                if self.fail_count >= ITERATIONS_MAX:
                    self.fail_count = ITERATIONS_MAX
                    self.bad_variance = True
                    if self._last_warn_ns is None or \
                            v.sim_ns - self._last_warn_ns > WARNING_TIME_S * NS:
                        v.statustext(mav.MAV_SEVERITY_CRITICAL, "EKF variance")
                        self._last_warn_ns = v.sim_ns
                    self._event(v)
        elif self.fail_count > 0:
            self.fail_count -= 1
            if self.bad_variance and self.fail_count == 0:
                self.bad_variance = False
                self._off_event(v)

    def _over_threshold(self, v, ratios, thresh: float, filt_hz: float) -> bool:
        dt = 0.0 if self._last_ns is None else (v.sim_ns - self._last_ns) / NS
        self._last_ns = v.sim_ns
        pos = self.pos_filt.apply(ratios.pos, dt, filt_hz)
        vel = self.vel_filt.apply(ratios.vel, dt, filt_hz)
        if thresh <= 0:
            return False
        count = 1 if ratios.mag >= thresh else 0
        if vel >= 2.0 * thresh:         # no optical flow here
            count += 2
        elif vel >= thresh:
            count += 1
        return (pos >= thresh and count >= 1) or count >= 2

    def _event(self, v) -> None:
        self.failsafe = True
        if not v.armed:
            return
        if v.mode.number == CopterMode.LAND:
            return                      # LAND stops using position by itself (module text)
        action = int(v.store.host("FS_EKF_ACTION"))
        if not v.mode.requires_position and action != ACTION_LAND_EVEN_STABILIZE:
            return
        if action == ACTION_ALTHOLD and not v.radio_failsafe_active:
            v.set_mode_internal(CopterMode.ALT_HOLD, "EKF failsafe")
        else:
            v.set_mode_internal(CopterMode.LAND, "EKF failsafe")
        self.acted = True
        v.statustext(mav.MAV_SEVERITY_CRITICAL, f"EKF Failsafe: changed to {v.mode.name} Mode")

    def _off_event(self, v) -> None:
        if not self.failsafe:
            return
        self.failsafe = False
        if self.acted:
            self.acted = False
            v.statustext(mav.MAV_SEVERITY_CRITICAL, "EKF Failsafe Cleared")
