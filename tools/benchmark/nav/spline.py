"""The reference path of an AUTO mission: its straight legs and its spline legs as
ArduCopter 4.6 shapes them (AP_Math/SplineCurve.cpp, AC_WPNav.cpp set_spline_destination*),
so the cross-track error of every controller is measured against one curve.

A spline leg from origin O to destination D is the cubic Hermite curve
p(t) = O + v0 t + (3(D - O) - 2 v0 - v1) t^2 + (2(O - D) + v0 + v1) t^3, t in [0, 1], with
- v0: the previous leg's end tangent if it was a spline, its direction vector D_prev - O_prev
  if it was straight, zero when the leg starts from a stop (the first leg);
- v1: N - O when the next leg is a spline (N its destination), N - D when it is straight,
  zero when the mission ends at D;
- both scaled down together when |v0| + |v1| exceeds 4 |D - O| (SPLINE_FACTOR: a short leg
  between long ones would otherwise loop).
"""

from __future__ import annotations

import numpy as np

SPLINE_FACTOR = 4.0          # SplineCurve.cpp: the longest tangents a leg's length allows
SAMPLES_PER_M = 10.0         # reference points per metre of leg (10 cm apart at most)


def leg_tangents(points: np.ndarray, spline: list[bool]) -> list[tuple]:
    """(v0, v1) of every leg i from points[i] to points[i + 1]; spline[i] says whether leg i
    is a spline leg. Straight legs get (None, None)."""
    n = len(points) - 1
    out: list[tuple] = []
    prev_end = None                     # the last spline leg's v1, if the previous leg was one
    for i in range(n):
        o, d = points[i], points[i + 1]
        if not spline[i]:
            out.append((None, None))
            prev_end = None
            continue
        if i == 0:
            v0 = np.zeros(2)
        elif spline[i - 1]:
            v0 = prev_end
        else:
            v0 = points[i] - points[i - 1]
        if i + 1 >= n:
            v1 = np.zeros(2)
        elif spline[i + 1]:
            v1 = points[i + 2] - o
        else:
            v1 = points[i + 2] - d
        prev_end = v1
        out.append((v0, v1))
    return out


def hermite(o, d, v0, v1, t: np.ndarray) -> np.ndarray:
    """Points of the spline leg at the parameters t (shape (len(t), 2))."""
    length = float(np.linalg.norm(d - o))
    total = float(np.linalg.norm(v0) + np.linalg.norm(v1))
    if total > SPLINE_FACTOR * length > 0.0:
        scale = SPLINE_FACTOR * length / total
        v0, v1 = v0 * scale, v1 * scale
    t = t[:, None]
    c2 = 3.0 * (d - o) - 2.0 * v0 - v1
    c3 = 2.0 * (o - d) + v0 + v1
    return o + v0 * t + c2 * t * t + c3 * t * t * t


def reference_path(start_ne, waypoints) -> tuple[np.ndarray, np.ndarray]:
    """(points (M, 2), leg index of each point) of the whole mission from start_ne through
    each Waypoint (tools/benchmark/nav/plans.py), densely sampled."""
    pts = np.array([start_ne] + [(w.north_m, w.east_m) for w in waypoints], dtype=float)
    tangents = leg_tangents(pts, [w.spline for w in waypoints])
    out, legs = [], []
    for i, (v0, v1) in enumerate(tangents):
        o, d = pts[i], pts[i + 1]
        n = max(2, int(np.ceil(np.linalg.norm(d - o) * SAMPLES_PER_M)) + 1)
        t = np.linspace(0.0, 1.0, n)
        seg = o + (d - o) * t[:, None] if v0 is None else hermite(o, d, v0, v1, t)
        out.append(seg)
        legs.append(np.full(n, i))
    return np.vstack(out), np.concatenate(legs)


def distance_to_path(path: np.ndarray, xy: np.ndarray, chunk: int = 256) -> np.ndarray:
    """Horizontal distance of each point of xy (K, 2) to the sampled path (M, 2): the
    nearest segment between consecutive path points (exact for a polyline)."""
    a, b = path[:-1], path[1:]
    ab = b - a
    ab2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
    out = np.empty(len(xy))
    for s in range(0, len(xy), chunk):
        p = xy[s:s + chunk, None, :]                         # (k, 1, 2)
        t = np.clip(((p - a) * ab).sum(axis=2) / ab2, 0.0, 1.0)
        q = a + t[..., None] * ab
        out[s:s + chunk] = np.sqrt(((p - q) ** 2).sum(axis=2)).min(axis=1)
    return out
