"""Frame conversions of the bridge, each in exactly one function.

Conventions: body FRD, world NED, ZYX Euler angles (yaw psi, pitch theta,
roll phi) as JSBSim reports them, quaternions scalar first and rotating body
FRD vectors into NED (v_ned = q * v_frd * q^-1), as PX4 and ArduPilot do.
Scalar math (no numpy): these run on the physics hot path.
"""

from __future__ import annotations

import math

_TWO_PI = 2.0 * math.pi


def quat_from_euler(phi: float, theta: float, psi: float) -> tuple[float, float, float, float]:
    """ZYX Euler (rad) -> unit quaternion (w, x, y, z), body FRD -> NED."""
    cr, sr = math.cos(0.5 * phi), math.sin(0.5 * phi)
    cp, sp = math.cos(0.5 * theta), math.sin(0.5 * theta)
    cy, sy = math.cos(0.5 * psi), math.sin(0.5 * psi)
    return (cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy)


def euler_from_quat(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Unit quaternion (w, x, y, z), body FRD -> NED -> ZYX Euler (roll, pitch, yaw) [rad],
    yaw in [-pi, pi]: quat_from_euler's inverse."""
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def ned_to_frd(phi: float, theta: float, psi: float, v_ned) -> tuple[float, float, float]:
    """Rotate a NED vector into body FRD: v_frd = R(phi) R(theta) R(psi) v_ned."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    cps, sps = math.cos(psi), math.sin(psi)
    n, e, d = v_ned
    # First yaw about down, then pitch about the new right axis, then roll about forward.
    x1 = cps * n + sps * e
    y1 = -sps * n + cps * e
    x2 = cth * x1 - sth * d
    z2 = sth * x1 + cth * d
    return (x2, cph * y1 + sph * z2, -sph * y1 + cph * z2)


def wrap_pi(angle_rad: float) -> float:
    """Wrap to [-pi, pi) (JSBSim's psi is in [0, 2 pi))."""
    return (angle_rad + math.pi) % _TWO_PI - math.pi


def wind_from_to_ned(speed_m_s: float, from_deg: float) -> tuple[float, float, float]:
    """Meteorological wind (speed, direction it blows FROM) -> air velocity in NED."""
    to_rad = math.radians(from_deg + 180.0)
    return (speed_m_s * math.cos(to_rad), speed_m_s * math.sin(to_rad), 0.0)
