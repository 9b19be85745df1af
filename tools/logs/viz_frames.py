"""Frames for the viewable log channels: NED/FRD rows -> Foxglove's ENU/FLU world, vectorized.

The simulator and the FC work in NED (world) and FRD (body); Foxglove's 3D
panel draws a z-up world, so the viewable channels use the ROS convention
(REP 103): frame "world" is ENU (x east, y north, z up) and "base_link" is
FLU (x forward, y left, z up). Each conversion happens here once, on whole
columns of a batch (numpy arrays of n rows), never per sample in Python.
Euler angles are the aerospace ZYX angles of the FRD -> NED attitude (the
ones the FC reports), so the plotted roll/pitch/yaw read as the pilot's.
"""

from __future__ import annotations

import math

import numpy as np

_H = math.sqrt(0.5)
# v_enu = R v_ned: swap north/east, flip down -> up (a half turn about the NE diagonal).
Q_ENU_FROM_NED = np.array([0.0, _H, _H, 0.0])          # w, x, y, z
# v_frd = R v_flu: a half turn about the forward axis flips left/up to right/down.
Q_FRD_FROM_FLU = np.array([0.0, 1.0, 0.0, 0.0])


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a*b of (..., 4) w, x, y, z quaternions (rotation b, then a)."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


# q_enu_flu = Q_ENU_FROM_NED * q * Q_FRD_FROM_FLU is linear in q: one 4x4 matrix.
_M_ENU_FLU = np.stack([quat_mul(quat_mul(Q_ENU_FROM_NED, e), Q_FRD_FROM_FLU)
                       for e in np.eye(4)], axis=0)


def q_enu_flu(q_ned_frd: np.ndarray) -> np.ndarray:
    """(n, 4) attitudes FRD -> NED (w, x, y, z) as FLU -> ENU, the base_link rotation."""
    return np.asarray(q_ned_frd, dtype=np.float64) @ _M_ENU_FLU


def ned_to_enu(v_ned: np.ndarray) -> np.ndarray:
    """(n, 3) NED vectors as ENU (east, north, up)."""
    v = np.asarray(v_ned, dtype=np.float64)
    return np.stack([v[:, 1], v[:, 0], -v[:, 2]], axis=-1)


def frd_to_flu(v_frd: np.ndarray) -> np.ndarray:
    """(n, 3) FRD body vectors as FLU (forward, left, up)."""
    v = np.asarray(v_frd, dtype=np.float64)
    return np.stack([v[:, 0], -v[:, 1], -v[:, 2]], axis=-1)


def euler_from_quat(q_wxyz: np.ndarray) -> np.ndarray:
    """(n, 3) roll, pitch, yaw [rad] (ZYX) of (n, 4) FRD -> NED attitudes."""
    q = np.asarray(q_wxyz, dtype=np.float64)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return np.stack([roll, pitch, yaw], axis=-1)


def quat_from_euler(euler_rad: np.ndarray) -> np.ndarray:
    """(n, 4) FRD -> NED attitudes (w, x, y, z) from (n, 3) ZYX roll, pitch, yaw [rad]."""
    e = np.asarray(euler_rad, dtype=np.float64) * 0.5
    cr, sr = np.cos(e[:, 0]), np.sin(e[:, 0])
    cp, sp = np.cos(e[:, 1]), np.sin(e[:, 1])
    cy, sy = np.cos(e[:, 2]), np.sin(e[:, 2])
    return np.stack([cr * cp * cy + sr * sp * sy,
                     sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy], axis=-1)


def quat_x_to(v: np.ndarray) -> np.ndarray:
    """(n, 4) rotations taking the +x axis onto the direction of each (n, 3) vector
    (an arrow primitive points along its pose's +x); identity for a zero vector."""
    v = np.asarray(v, dtype=np.float64)
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    u = np.divide(v, norm, out=np.zeros_like(v), where=norm > 0)
    # Half-way quaternion between x and u: (1 + x.u, x cross u), normalised.
    q = np.stack([1.0 + u[:, 0], np.zeros(len(u)), -u[:, 2], u[:, 1]], axis=-1)
    qn = np.linalg.norm(q, axis=-1, keepdims=True)
    flip = qn[:, 0] < 1e-9                      # u = -x: any half turn about z will do
    q[flip] = (0.0, 0.0, 0.0, 1.0)
    qn[flip] = 1.0
    q /= qn
    q[norm[:, 0] == 0] = (1.0, 0.0, 0.0, 0.0)
    return q
