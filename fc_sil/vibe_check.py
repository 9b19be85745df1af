"""Vibration failsafe: ArduCopter 4.6's check_vibration (ArduCopter/ekf_check.cpp), FS_VIBE_ENABLE.

Accelerometer aliasing (vibration, clipping) biases the vertical acceleration, so the vertical
estimate runs away from both the barometer and the GNSS vertical velocity in the same sense.
Detected, at 10 Hz, when either:

* the down-velocity innovation (estimate - GNSS) and the down-position innovation
  (estimate - baro) are both positive and the low-passed velocity test ratio (ekf_check.py's
  filter) is above 1; or
* the estimator's own bad-IMU test fires (EKF3 is_vibration_affected): both innovations of
  one sign and each beyond 3 sigma (EK3_ALT_M_NSE, EK3_VELD_M_NSE); the test tightens to 2 and
  1 sigma within 20 s and 15 s of the last event and the verdict holds for 10 s after it.

With FS_VIBE_ENABLE 1, armed, and a mode with automatic throttle, 1 s of detection switches
the altitude controller to its vibration-resistant law, "Vibration compensation ON"
(CRITICAL); it goes back 15 s after the detection last held, "Vibration compensation OFF".
(As ArduCopter: when the detection is gone at the first check after switching on, the 15 s
count from boot and it switches off at once.)

The law: AC_PosControl's vibration override replaces the measured-acceleration PID by a
feed-forward of the acceleration target and a slow integrator of the climb-rate error; the C
core's altitude controller has it (fc_alt_ctrl.h, FlightCore.set_vibe_comp).
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

NS = 1_000_000_000
PERIOD_NS = NS // 10
DETECT_S = 1.0                  # ArduCopter: failure persisted for 1 s
CLEAR_S = 15.0                  # and off 15 s after it last held
BAD_IMU_HOLD_S = 10.0           # EKF3 BAD_IMU_DATA_HOLD_MS


class VibrationCheck:
    def __init__(self):
        self.high_vibes = False
        self.start_ns = 0
        self.clear_ns = 0
        self.bad_imu = False
        self._bad_imu_ns = None
        self._next_ns = 0
        self._fix_ns = None
        self._innov = None              # (down-velocity, down-position) of the last fix

    def check(self, v, ekf) -> None:
        self._bad_imu_test(v)
        if v.sim_ns < self._next_ns:
            return
        self._next_ns = v.sim_ns - v.sim_ns % PERIOD_NS + PERIOD_NS
        now = v.sim_ns
        both_positive = self._innov is not None and self._innov[0] > 0 and self._innov[1] > 0
        detected = (both_positive and ekf.vel_filt.value > 1.0) or self.bad_imu
        act = (int(v.store.host("FS_VIBE_ENABLE")) == 1 and detected and v.armed
               and not v.mode.manual_throttle)
        if not self.high_vibes:
            if not act:
                self.start_ns = now
            if now - self.start_ns > DETECT_S * NS:
                self.clear_ns = 0
                self._switch(v, True)
        else:
            if act:
                self.clear_ns = now
            if now - self.clear_ns > CLEAR_S * NS:
                self.start_ns = self.clear_ns = 0
                self._switch(v, False)

    def _switch(self, v, on: bool) -> None:
        self.high_vibes = on
        v.core.set_vibe_comp(on)
        v.statustext(mav.MAV_SEVERITY_CRITICAL,
                     "Vibration compensation ON" if on else "Vibration compensation OFF")

    def _bad_imu_test(self, v) -> None:
        """At each new GNSS fix: EKF3's same-sign vertical innovation test."""
        g = v.gnss
        if g is None or g["sim_ns"] == self._fix_ns or g["fix_type"] < 3 or not v.armed:
            return
        self._fix_ns = g["sim_ns"]
        inn = v.core.innovations()
        vel_d = -v.climb_m_s - g["vel_ned_m_s"][2]
        pos_d = inn["baro_innov_m"]        # (-alt_est) - (-baro_alt)
        self._innov = (vel_d, pos_d)
        get = v.store.host
        since = None if self._bad_imu_ns is None else (v.sim_ns - self._bad_imu_ns) / NS
        gain = 9.0 if since is None or since > 2 * BAD_IMU_HOLD_S else \
            4.0 if since > 1.5 * BAD_IMU_HOLD_S else 1.0
        if (pos_d * vel_d > 0 and pos_d * pos_d > gain * get("EK3_ALT_M_NSE") ** 2
                and vel_d * vel_d > gain * get("EK3_VELD_M_NSE") ** 2):
            self._bad_imu_ns = v.sim_ns
            since = 0.0
        self.bad_imu = since is not None and since < BAD_IMU_HOLD_S
