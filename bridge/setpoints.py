"""Scripted setpoints: the scenario's flight profile as SETPOINT record events.

The profile: at step 1 the take-off altitude with level attitude and the home
heading; then [[setpoint]] entries change it:
- tilt: roll or pitch doublets (+A, level, -A, level) or single pulses (+A, level),
  as steps or linear ramps of ramp_s; `repeat` times every `period_s`, each
  repetition with its own drawn amplitude and hold. Tilts on the same axis add.
- altitude / yaw: go to a new value at start_s, stepped or ramped over ramp_s.
Everything is compiled at start into a list of (step, roll, pitch, yaw, alt)
events: one at each change, and at `setpoint_rate_hz` while a ramp runs, so
the per-step cost is one integer compare. Angles in rad, yaw wrapped to
[-pi, pi), altitude in m above home; mask = attitude | altitude | yaw valid.
"""

from __future__ import annotations

import bisect
import math

from silbridge.bridge.frames import wrap_pi

MASK_ATTITUDE = 1
MASK_ALTITUDE = 2
MASK_YAW = 4
MASK_ALL = MASK_ATTITUDE | MASK_ALTITUDE | MASK_YAW


class PiecewiseLinear:
    """Knots (t, v); equal times make a step (the later knot wins at that instant)."""

    def __init__(self, v0: float):
        self.t = [0.0]
        self.v = [v0]

    def add(self, t: float, v: float) -> None:
        if t < self.t[-1]:
            raise ValueError("knots must be added in time order")
        self.t.append(t)
        self.v.append(v)

    def at(self, t: float) -> float:
        i = bisect.bisect_right(self.t, t) - 1
        if i < 0:
            return self.v[0]
        if i + 1 < len(self.t) and self.t[i + 1] > self.t[i]:
            t0, t1 = self.t[i], self.t[i + 1]
            return self.v[i] + (self.v[i + 1] - self.v[i]) * (t - t0) / (t1 - t0)
        return self.v[i]

    def ramps(self):
        """(t0, t1) of every segment whose value changes over time."""
        return [(self.t[i], self.t[i + 1]) for i in range(len(self.t) - 1)
                if self.t[i + 1] > self.t[i] and self.v[i + 1] != self.v[i]]


def _tilt_curve(sp, r: int) -> list[tuple[float, float]]:
    """Knots of repetition r of a tilt entry, as (t, value_deg), relative to 0."""
    t0 = sp.start_s + r * sp.period_s
    a = sp.amplitude_deg[r]
    hold = sp.hold_s[r]
    ramp = sp.ramp_s[r] if sp.shape == "ramp" else 0.0
    # A doublet passes through level between +A and -A: every step or ramp is then
    # A (20 to 35 deg in S4, the paper's range), never the 2A of a direct +A -> -A.
    levels = [a, 0.0, -a, 0.0] if sp.doublet else [a, 0.0]
    knots = [(t0, 0.0)]
    t, v = t0, 0.0
    for i, target in enumerate(levels):
        dur = ramp * abs(target - v) / abs(a) if a else 0.0
        t += dur
        knots.append((t, target))
        v = target
        if i < len(levels) - 1:
            t += hold
            knots.append((t, v))
    return knots


class SetpointProgram:
    def __init__(self, scenario, dt_ns: int, heading_rad: float):
        self.dt_ns = dt_ns
        dt_s = dt_ns * 1e-9
        duration_s = scenario.duration_s
        yaw0 = wrap_pi(heading_rad)
        tilt_curves = {"roll": [], "pitch": []}
        alt = PiecewiseLinear(scenario.takeoff_alt_m)
        yaw = PiecewiseLinear(yaw0)
        for sp in sorted(scenario.setpoints, key=lambda s: s.start_s):
            if sp.type == "tilt":
                for r in range(sp.repeat):
                    curve = PiecewiseLinear(0.0)
                    for t, v in _tilt_curve(sp, r):
                        curve.add(t, math.radians(v))
                    tilt_curves[sp.axis].append(curve)
            elif sp.type == "altitude":
                self._go_to(alt, sp.start_s, sp.altitude_m, sp.ramp_s)
            else:
                self._go_to(yaw, sp.start_s, wrap_pi(math.radians(sp.yaw_deg)), sp.ramp_s)
        curves = [alt, yaw] + tilt_curves["roll"] + tilt_curves["pitch"]

        def step_at(t_s):  # first step whose time k dt is >= t_s
            return max(1, -(-int(round(t_s * 1e9)) // dt_ns))

        steps = {1}
        every = max(1, int(round(1.0 / (scenario.setpoint_rate_hz * dt_s))))
        for c in curves:
            for t in c.t[1:]:
                steps.add(step_at(t))
            for t0, t1 in c.ramps():
                k0, k1 = step_at(t0), step_at(t1)
                steps.update(range(k0, k1 + 1, every))
                steps.add(k1)
        last_step = int(round(duration_s * 1e9)) // dt_ns
        self.events = []
        prev = None
        for k in sorted(s for s in steps if s <= last_step):
            t = k * dt_s
            val = (sum(c.at(t) for c in tilt_curves["roll"]),
                   sum(c.at(t) for c in tilt_curves["pitch"]),
                   wrap_pi(yaw.at(t)), alt.at(t))
            if val != prev:
                self.events.append((k, *val, MASK_ALL))
                prev = val
        self._next = 0
        self.next_step = self.events[0][0] if self.events else -1

    @staticmethod
    def _go_to(curve: PiecewiseLinear, t: float, value: float, ramp_s: float) -> None:
        t = max(t, curve.t[-1])
        start = curve.at(t)
        curve.add(t, start)
        curve.add(t + ramp_s, value)

    def pop(self):
        """The event of the current next_step: (step, roll, pitch, yaw, alt, mask)."""
        ev = self.events[self._next]
        self._next += 1
        self.next_step = self.events[self._next][0] if self._next < len(self.events) else -1
        return ev
