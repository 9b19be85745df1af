"""SCurve: the jerk-limited speed profile of one straight leg (WPNAV_SPEED, _ACCEL, _JERK).

ArduCopter flies a waypoint leg along a precomputed S-curve: the distance along the leg is a
function of time whose speed, acceleration, jerk and snap never exceed the leg's limits and
which comes to rest exactly at the leg's end. Each change of acceleration is one "jerk pulse"
as in ArduCopter's SCurve: the jerk rises to J along a raised cosine over tj, stays at J,
and falls back along a raised cosine over tj, where tj = pi J / (2 snap) bounds the snap
(AC_WPNav takes the snap from the attitude's input time constant: the lean, and so the
acceleration, cannot change faster than the attitude target does). A speed change is a
rising pulse, a stretch of constant acceleration if needed, and a falling pulse; a leg is a
speed change up, a cruise, a speed change down to rest. With snap 0 the pulses are plain
constant-jerk steps (the seven-segment profile).

A leg may start moving (``v0``, along the leg, at zero acceleration): the profile then
changes speed from v0 to its peak and back to rest. The peak speed is the largest that still
stops within the leg (found by bisection: the distance of a profile grows with its peak).
If even an immediate stop from v0 passes the end, the profile stops as fast as it may and
the leg's end clamps the position: the position controller absorbs the rest.

Units: metres, seconds. ``at(t)`` returns (s, v, a) along the leg.
"""

from __future__ import annotations

import math

# piece kinds: constant jerk, raised-cosine rise of the jerk to J, raised-cosine fall from J
_CONST, _RISE, _FALL = 0, 1, 2


def _pulse(tj: float, t2: float, jerk: float) -> list[tuple[int, float, float]]:
    """One jerk pulse: acceleration change jerk * (tj + t2), taking 2 tj + t2."""
    if tj <= 0.0:
        return [(_CONST, t2, jerk)]
    return [(_RISE, tj, jerk), (_CONST, t2, jerk), (_FALL, tj, jerk)]


def _speed_change(dv: float, accel: float, jerk: float, tj: float
                  ) -> list[tuple[int, float, float]]:
    """Pieces (kind, duration, jerk) changing speed by dv, from and to zero acceleration.

    A pulse reaching acceleration A lasts tj + A/J and changes the speed by A (tj + A/J)
    (the acceleration profile is symmetric); a constant-acceleration stretch adds the rest."""
    if dv == 0.0:
        return []
    sign = 1.0 if dv > 0.0 else -1.0
    dv = abs(dv)
    if tj > 0.0 and accel < jerk * tj:
        jerk = accel / tj                 # the snap ramps alone reach accel: lower the jerk
    full = accel * (tj + accel / jerk)
    if dv >= full:
        a, ta = accel, dv / accel - (tj + accel / jerk)
    else:
        a = 0.5 * jerk * (-tj + math.sqrt(tj * tj + 4.0 * dv / jerk))
        ta = 0.0
        if tj > 0.0 and a < jerk * tj:    # too small for a constant-jerk part
            a = dv / (2.0 * tj)
            jerk = a / tj
    t2 = max(0.0, a / jerk - tj)
    return (_pulse(tj, t2, sign * jerk) + [(_CONST, ta, 0.0)]
            + _pulse(tj, t2, -sign * jerk))


def _change_time(dv: float, accel: float, jerk: float, tj: float) -> float:
    return sum(d for _, d, _ in _speed_change(dv, accel, jerk, tj))


def _change_dist(v_from: float, v_to: float, accel: float, jerk: float, tj: float) -> float:
    # the S-shaped speed change is point-symmetric about its middle: mean speed = (v0+v1)/2
    return 0.5 * (v_from + v_to) * _change_time(v_to - v_from, accel, jerk, tj)


class SCurve:
    """Rest-at-the-end profile over ``length_m`` starting at speed ``v0``."""

    def __init__(self, length_m: float, speed_m_s: float, accel_m_s2: float, jerk_m_s3: float,
                 v0_m_s: float = 0.0, snap_m_s4: float = 0.0):
        self.length_m = max(0.0, float(length_m))
        self.speed = max(1e-3, float(speed_m_s))
        self.accel = max(1e-3, float(accel_m_s2))
        self.jerk = max(1e-3, float(jerk_m_s3))
        # the raised-cosine ramp of the jerk peaks at snap pi J / (2 tj)
        self.tj = math.pi * self.jerk / (2.0 * snap_m_s4) if snap_m_s4 > 0.0 else 0.0
        v0 = max(0.0, float(v0_m_s))
        self.v_peak = self._peak(v0)
        pieces = self._change(self.v_peak - v0)
        used = self._dist(v0, self.v_peak) + self._dist(self.v_peak, 0.0)
        if self.v_peak > 0.0 and used < self.length_m:
            pieces.append((_CONST, (self.length_m - used) / self.v_peak, 0.0))
        pieces += self._change(-self.v_peak)
        # segment start states (t, s, v, a) so at(t) is one evaluation
        self._segs = []
        t = s = a = 0.0
        v = v0
        for kind, dur, j in pieces:
            if dur <= 0.0:
                continue
            self._segs.append((t, dur, kind, j, s, v, a))
            s, v, a = _piece(kind, s, v, a, j, dur, dur)
            t += dur
        self.duration_s = t

    def _change(self, dv: float):
        return _speed_change(dv, self.accel, self.jerk, self.tj)

    def _dist(self, v_from: float, v_to: float) -> float:
        return _change_dist(v_from, v_to, self.accel, self.jerk, self.tj)

    def _peak(self, v0: float) -> float:
        def total(vp):
            return self._dist(v0, vp) + self._dist(vp, 0.0)
        if total(self.speed) <= self.length_m:
            return self.speed
        if v0 >= self.speed or total(v0) > self.length_m:
            return v0                     # no room to speed up: brake at once
        lo, hi = v0, self.speed           # the distance grows with the peak from v0 up
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            if total(mid) <= self.length_m:
                lo = mid
            else:
                hi = mid
        return lo

    def at(self, t_s: float) -> tuple[float, float, float]:
        """(distance along the leg, speed, acceleration) at time t after the start."""
        if not self._segs:
            return self.length_m, 0.0, 0.0
        if t_s <= 0.0:
            _, _, _, _, s, v, a = self._segs[0]
            return s, v, a
        for t0, dur, kind, j, s, v, a in self._segs:
            if t_s < t0 + dur:
                s, v, a = _piece(kind, s, v, a, j, t_s - t0, dur)
                return min(s, self.length_m), v, a
        return self.length_m, 0.0, 0.0

    def finished(self, t_s: float) -> bool:
        return t_s >= self.duration_s


def _piece(kind: int, s: float, v: float, a: float, j: float, t: float, dur: float
           ) -> tuple[float, float, float]:
    """State t into a piece of duration dur starting at (s, v, a) with jerk (peak) j."""
    if kind == _CONST:
        return (s + v * t + a * t * t / 2.0 + j * t * t * t / 6.0,
                v + a * t + j * t * t / 2.0,
                a + j * t)
    b = math.pi / dur
    sb, cb = math.sin(b * t), math.cos(b * t)
    h = 0.5 * j
    if kind == _RISE:     # jerk = J/2 (1 - cos(pi t / tj))
        return (s + v * t + a * t * t / 2.0 + h * (t ** 3 / 6.0 - t / b ** 2 + sb / b ** 3),
                v + a * t + h * (t * t / 2.0 + (cb - 1.0) / b ** 2),
                a + h * (t - sb / b))
    # _FALL: jerk = J/2 (1 + cos(pi t / tj))
    return (s + v * t + a * t * t / 2.0 + h * (t ** 3 / 6.0 + t / b ** 2 - sb / b ** 3),
            v + a * t + h * (t * t / 2.0 + (1.0 - cb) / b ** 2),
            a + h * (t + sb / b))
