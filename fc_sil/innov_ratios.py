"""The estimator's innovation test ratios and EKF_STATUS_REPORT, as ArduCopter's EKF3 reports them.

Four normalised ratios, each |innovation| / (gate * innovation sigma), the square root of
EKF3's test ratio, so 1.0 sits on the gate (AP_NavEKF3_Outputs.cpp getVariances):

* velocity and horizontal position: the GNSS fix against the delayed estimate, computed by the
  gate that decides whether the fix is fused (gnss_gate.py has the variance definitions);
* height: the barometer altitude against the C core's vertical filter (its last in-flight
  innovation), gate EK3_HGT_I_GATE, sigma EK3_ALT_M_NSE (the filter's own averaging makes its
  variance small beside the baro's noise; it is left out);
* compass: the magnetometer heading against the attitude estimate's yaw (the C core's Mahony
  heading error), gate EK3_YAW_I_GATE, sigma EK3_YAW_M_NSE: EKF3's simple heading fusion.
  ArduCopter in flight fuses the three field axes instead (EK3_MAG_I_GATE, EK3_MAG_M_NSE);
  the heading form is what our filter measures.

Flags as EKF3's updateFilterStatus sets them for a GNSS-aided copter, including ArduPilot's
gps_glitching bit (1 << 15, not in the MAVLink enum): the innovations failed (ratio >= 1)
for 1 s, cleared after 10 s without a failing fix (calcGpsGoodForFlight). Reported
at the rate a GCS asks (EKF_STATUS_REPORT is in ArduCopter's EXTRA3 stream).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

NS = 1_000_000_000
EKF_GPS_GLITCHING = 1 << 15     # ArduPilot's bit for nav_filter_status.gps_glitching
GLITCH_FAIL_S = 1.0             # calcGpsGoodForFlight: fail for 1 s ...
GLITCH_PASS_S = 10.0            # ... pass for 10 s
GLITCH_WARN_RATIO = 0.7         # a ratio above this restarts the pass timer
TILT_DRIFT_MAX_S = 15.0         # EKF3 tiltDriftTimeMax_ms: no aiding this long -> AID_NONE


class InnovationRatios:
    """Updated once per outer-loop step (Vehicle -> FailsafeMonitor); read by the checks and
    by the snapshot (EKF_STATUS_REPORT)."""

    def __init__(self):
        self.pos = 0.0
        self.vel = 0.0
        self.hgt = 0.0
        self.mag = 0.0
        self.gps_glitching = False
        self._last_baro_ns = None
        self._pass_ns = None         # last time both GNSS ratios were below 1
        self._fail_ns = None         # last time one was above GLITCH_WARN_RATIO

    def update(self, v) -> None:
        gate = v.est.gate
        self.pos, self.vel = gate.pos_ratio, gate.vel_ratio
        get = v.store.host
        inn = v.core.innovations()
        if inn["have_baro"] and inn["last_baro_ns"] != self._last_baro_ns:
            self._last_baro_ns = inn["last_baro_ns"]
            g = max(get("EK3_HGT_I_GATE") / 100.0, 1.0)
            self.hgt = abs(inn["baro_innov_m"]) / (g * get("EK3_ALT_M_NSE"))
        if inn["heading_valid"] and v.cfg.compass_use:
            g = max(get("EK3_YAW_I_GATE") / 100.0, 1.0)
            self.mag = abs(inn["heading_err_rad"]) / (g * get("EK3_YAW_M_NSE"))
        else:
            self.mag = 0.0
        self._glitch_hysteresis(v)

    def _glitch_hysteresis(self, v) -> None:
        t = v.sim_ns
        if not v.est.valid or self._pass_ns is None:    # (or the estimate was valid at once)
            self._pass_ns = self._fail_ns = t
            self.gps_glitching = False
            return
        if self.pos < 1.0 and self.vel < 1.0:
            self._pass_ns = t
        elif self.pos > GLITCH_WARN_RATIO or self.vel > GLITCH_WARN_RATIO:
            self._fail_ns = t
        if t - self._pass_ns > GLITCH_FAIL_S * NS:
            self.gps_glitching = True
        elif t - self._fail_ns > GLITCH_PASS_S * NS:
            self.gps_glitching = False

    # ---- EKF_STATUS_REPORT ---------------------------------------------------------------

    def flags(self, v) -> int:
        if v.imu_run_s < 1.0 or v.trust < 0.5:
            return mav.EKF_UNINITIALIZED
        t = v.sim_ns
        f = mav.EKF_ATTITUDE | mav.EKF_VELOCITY_VERT | mav.EKF_POS_VERT_ABS
        gate = v.est.gate
        if v.est.has_position(t):
            f |= (mav.EKF_VELOCITY_HORIZ | mav.EKF_POS_HORIZ_REL | mav.EKF_POS_HORIZ_ABS
                  | mav.EKF_PRED_POS_HORIZ_REL | mav.EKF_PRED_POS_HORIZ_ABS)
        elif v.est.valid and gate.vel_aiding(t):
            f |= mav.EKF_VELOCITY_HORIZ
        aided = v.est.valid and min(_since(t, gate.last_pos_pass_ns),
                                    _since(t, gate.last_vel_pass_ns)) <= TILT_DRIFT_MAX_S
        if not aided:
            f |= mav.EKF_CONST_POS_MODE
        if self.gps_glitching:
            f |= EKF_GPS_GLITCHING
        return f

    def status_fields(self, v) -> dict:
        """The snapshot's EKF_STATUS_REPORT fields."""
        return dict(ekf_flags=self.flags(v), ekf_vel_var=self.vel, ekf_pos_h_var=self.pos,
                    ekf_pos_v_var=self.hgt, ekf_compass_var=self.mag)


def _since(t_ns: int, then_ns: int | None) -> float:
    return math.inf if then_ns is None else (t_ns - then_ns) / NS
