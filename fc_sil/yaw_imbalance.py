"""Yaw-imbalance warning: ArduCopter 4.6's yaw_imbalance_check (ArduCopter/crash_check.cpp).

A yaw rate integrator that holds most of its limit means the motors are not balanced in yaw
(a badly calibrated ESC, a twisted arm, a damaged propeller). While armed and flying, with
ATC_RAT_YAW_I above 0, the thrust boost off and FLIGHT_OPTIONS bit 1 clear: the magnitude of
the yaw I term, low-passed at 0.05 Hz (never above the I term itself), above 75 % of
ATC_RAT_YAW_IMAX, or the unfiltered term at the limit, gives "Yaw Imbalance <N>%"
(EMERGENCY), N the filtered term in percent of the full output, at most every 10 s.
A warning only; it takes no action.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from .ekf_check import LowPass

NS = 1_000_000_000
IMAX_THRESHOLD = 0.75           # YAW_IMBALANCE_IMAX_THRESHOLD
WARN_S = 10.0                   # YAW_IMBALANCE_WARN_MS
FILT_HZ = 0.05                  # Copter::yaw_I_filt cutoff
US_PER_NORM = 500.0             # rate-loop terms are us about the mixer centre (fc_params.def)
OPT_DISABLE_YAW_IMBALANCE = 2   # FLIGHT_OPTIONS bit 1


class YawImbalanceCheck:
    def __init__(self):
        self.filt = LowPass()
        self._last_ns = None
        self._warned_ns = None

    def check(self, v, boost: bool) -> None:
        dt = 0.0 if self._last_ns is None else (v.sim_ns - self._last_ns) / NS
        self._last_ns = v.sim_ns
        core, st = v.core, v.status
        if (int(v.store.host("FLIGHT_OPTIONS")) & OPT_DISABLE_YAW_IMBALANCE
                or not core.get_param("ATC_RAT_YAW_I") > 0):
            return
        if boost or not v.armed or not v.airborne or st is None:
            self.filt.value = 0.0
            return
        i_term = float(st["pid_i"][2]) / US_PER_NORM
        i_filt = abs(self.filt.apply(i_term, dt, FILT_HZ))
        if i_filt > abs(i_term):
            self.filt.value = i_term       # never larger than the I term itself (next step)
        imax = core.get_param("ATC_RAT_YAW_IMAX")
        at_limit = math.isclose(i_term, imax, rel_tol=1e-5)     # float32 terms
        if imax > 0 and (i_filt > IMAX_THRESHOLD * imax or at_limit):
            if self._warned_ns is None or v.sim_ns - self._warned_ns > WARN_S * NS:
                self._warned_ns = v.sim_ns
                v.statustext(mav.MAV_SEVERITY_EMERGENCY, f"Yaw Imbalance {i_filt * 100:.0f}%")
