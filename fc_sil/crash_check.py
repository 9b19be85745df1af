"""Crash check: ArduCopter 4.6's crash_check (ArduCopter/crash_check.cpp), FS_CRASH_CHECK.

While armed, not landed and FS_CRASH_CHECK is 1, the vehicle counts as crashed when all hold
at once: its 1 Hz low-passed earth-frame acceleration (gravity removed) is below 3 m/s^2
(it is not falling or being thrown), it leans more than 15 deg, its thrust vector is more than
30 deg from the target's, and it moves slower than 10 m/s. Two seconds of that (sim time)
disarm it with "Crash: Disarming: AngErr=<err>><30>, Accel=<acc><<3.0>" (EMERGENCY).
ArduCopter also exempts ACRO and FLIP (we have neither) and standby / force-flying (neither).

Angles come from the estimate, as ArduCopter's AHRS; the angle error is the angle between the
target's and the estimate's body z axes (AC_AttitudeControl's thrust error angle).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm.records import NS_PER_S as NS

from .ekf_check import LowPass
from .held_for import HeldFor

TRIGGER_S = 2.0                 # CRASH_CHECK_TRIGGER_SEC
ANGLE_DEVIATION_DEG = 30.0      # CRASH_CHECK_ANGLE_DEVIATION_DEG
ANGLE_MIN_DEG = 15.0            # CRASH_CHECK_ANGLE_MIN_DEG
SPEED_MAX_M_S = 10.0            # CRASH_CHECK_SPEED_MAX
ACCEL_MAX_M_S2 = 3.0            # CRASH_CHECK_ACCEL_MAX
ACCEL_LPF_HZ = 1.0              # LAND_DETECTOR_ACCEL_LPF_CUTOFF


def body_z_ned(roll: float, pitch: float, yaw: float) -> tuple[float, float, float]:
    """The body z (down) axis in NED for ZYX Euler angles."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (cr * sp * cy + sr * sy, cr * sp * sy - sr * cy, cr * cp)


def thrust_error_deg(target_rpy, est_rpy) -> float:
    a, b = body_z_ned(*target_rpy), body_z_ned(*est_rpy)
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    return math.degrees(math.acos(max(-1.0, min(1.0, dot))))


def lean_deg(roll: float, pitch: float) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch)))))


class CrashCheck:
    def __init__(self):
        self.acc_filt = [LowPass(), LowPass(), LowPass()]
        self._held = HeldFor(TRIGGER_S)
        self._last_ns = None
        self.crashed = False

    def filtered_accel(self, v) -> float:
        dt = 0.0 if self._last_ns is None else (v.sim_ns - self._last_ns) / NS
        self._last_ns = v.sim_ns
        a = v.est.acc_ned_m_s2
        return math.sqrt(sum(f.apply(x, dt, ACCEL_LPF_HZ) ** 2 for f, x in zip(self.acc_filt, a)))

    def check(self, v) -> None:
        acc = self.filtered_accel(v)     # filtered every step, as the land detector's
        st = v.status
        if not v.armed or not v.airborne or st is None or not v.store.host("FS_CRASH_CHECK"):
            self._held.update(False, v.sim_ns)
            return
        roll, pitch, _ = v.euler_rad
        err = thrust_error_deg(tuple(float(x) for x in st["att_target_rad"]), v.euler_rad)
        vn, ve = v.est.vel_ne_m_s
        speed = math.sqrt(vn * vn + ve * ve + v.climb_m_s * v.climb_m_s)
        crashed = (acc < ACCEL_MAX_M_S2 and lean_deg(roll, pitch) > ANGLE_MIN_DEG
                   and err > ANGLE_DEVIATION_DEG and speed < SPEED_MAX_M_S)
        if self._held.update(crashed, v.sim_ns):
            self.crashed = True
            v.statustext(mav.MAV_SEVERITY_EMERGENCY,
                         f"Crash: Disarming: AngErr={err:.0f}>{ANGLE_DEVIATION_DEG:.0f}, "
                         f"Accel={acc:.1f}<{ACCEL_MAX_M_S2:.1f}")
            v.failsafe_disarm()
