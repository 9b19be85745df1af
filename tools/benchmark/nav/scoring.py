"""Metrics of a flight against its plan, from ground truth only (pure functions).

A `Track` is the vehicle's true trajectory (the run log's /gt_nav and /gt_att); the times
in a `Flight` (tools/benchmark/nav/scripts.py) are on the same clock. Nothing an autopilot
reports about itself is scored, so every controller is measured by the same ruler.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from silbridge.tools.benchmark.nav.spline import distance_to_path, reference_path

ARRIVE_M = 1.0          # N1/N3: arrived = first true horizontal distance below this [m]
TRACK_SETTLE_S = 2.0    # N2: each leg scored from this long after its command to its end [s]
JERK_BIN_S = 0.1        # N3/N4: velocity averaged over bins this long before differencing:
                        # the path's acceleration and jerk, not the attitude loop's ripple
XTRACK_HZ = 50.0        # N3/N4: cross-track sampled at this rate [Hz]
PASS_M = 3.0            # N3/N4: the waypoint before the last one counts as passed this close:
                        # a spline corner into a straight leg passes 1-2 m off its waypoint


@dataclass
class Track:
    """The true trajectory: times [s], NE position [m], height above home [m], NE velocity
    [m/s] and heading [rad], one row per ground-truth sample."""
    t_s: np.ndarray
    pos_ne: np.ndarray       # (K, 2)
    alt_m: np.ndarray
    vel_ne: np.ndarray       # (K, 2)
    yaw_rad: np.ndarray

    def window(self, t0: float, t1: float) -> "Track":
        m = (self.t_s >= t0) & (self.t_s < t1)
        return Track(self.t_s[m], self.pos_ne[m], self.alt_m[m], self.vel_ne[m],
                     self.yaw_rad[m])


def wrap_pi(a):
    """Angles wrapped into [-pi, pi): a yaw error of 359 deg is -1 deg."""
    return (np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi


def yaw_from_quat(q_wxyz: np.ndarray) -> np.ndarray:
    """Heading [rad] of FRD-in-NED quaternions (rows w, x, y, z)."""
    w, x, y, z = (q_wxyz[:, i].astype(float) for i in range(4))
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


# ---- N1: guided goto -----------------------------------------------------------------------
def goto_leg(track: Track, start_ne, target_ne, t_sent: float, t_end: float) -> dict:
    """One goto from start_ne to target_ne, commanded at t_sent, until the next command:
    overshoot = how far the vehicle went past the target along the leg's direction (0 if
    it never passed it); arrive_s = time from the command to the first true position within
    ARRIVE_M (NaN if never); peak_speed = the largest true horizontal speed."""
    w = track.window(t_sent, t_end)
    leg = np.asarray(target_ne, float) - np.asarray(start_ne, float)
    u = leg / max(float(np.linalg.norm(leg)), 1e-9)
    along = (w.pos_ne - np.asarray(target_ne, float)) @ u
    dist = np.linalg.norm(w.pos_ne - np.asarray(target_ne, float), axis=1)
    inside = np.flatnonzero(dist < ARRIVE_M)
    return {"overshoot_m": float(max(0.0, along.max())) if len(along) else math.nan,
            "arrive_s": float(w.t_s[inside[0]] - t_sent) if len(inside) else math.nan,
            "peak_speed_m_s": float(np.linalg.norm(w.vel_ne, axis=1).max())
            if len(w.t_s) else math.nan}


def score_goto(track: Track, targets, sent_s: list[float], end_s: float,
               start_ne=(0.0, 0.0)) -> dict:
    """N1's row: the worst overshoot, the mean arrival time, the top speed over the legs."""
    legs = []
    starts = [tuple(start_ne)] + [tuple(t) for t in targets[:-1]]
    ends = list(sent_s[1:]) + [end_s]
    for s, tgt, t0, t1 in zip(starts, targets, sent_s, ends):
        legs.append(goto_leg(track, s, tgt, t0, t1))
    return {"overshoot_m": max(g["overshoot_m"] for g in legs),
            "arrive_s": float(np.mean([g["arrive_s"] for g in legs])),
            "peak_speed_m_s": max(g["peak_speed_m_s"] for g in legs),
            "legs": legs}


# ---- N2: offboard velocity with yaw --------------------------------------------------------
def score_velocity(track: Track, legs, sent_s: list[float], end_s: float) -> dict:
    """N2's row: RMS of the true horizontal velocity error and of the heading error (wrapped)
    over each leg from TRACK_SETTLE_S after its command to its end; the largest heading error
    at the end of a leg (the heading the vehicle settled on)."""
    ends = list(sent_s[1:]) + [end_s]
    v_err, y_err, y_end = [], [], []
    for leg, t0, t1 in zip(legs, sent_s, ends):
        w = track.window(t0 + TRACK_SETTLE_S, t1)
        if not len(w.t_s):
            continue
        cmd = np.array([leg.vn_m_s, leg.ve_m_s])
        v_err.append(np.linalg.norm(w.vel_ne - cmd, axis=1))
        e = np.degrees(np.abs(wrap_pi(w.yaw_rad - math.radians(leg.yaw_deg))))
        y_err.append(e)
        y_end.append(float(e[-1]))
    if not v_err:
        return {"vel_rms_m_s": math.nan, "yaw_rms_deg": math.nan, "yaw_end_deg": math.nan}
    v, y = np.concatenate(v_err), np.concatenate(y_err)
    return {"vel_rms_m_s": float(np.sqrt(np.mean(v * v))),
            "yaw_rms_deg": float(np.sqrt(np.mean(y * y))),
            "yaw_end_deg": max(y_end)}


# ---- N3/N4: AUTO mission -------------------------------------------------------------------
def binned_velocity(track: Track, bin_s: float = JERK_BIN_S) -> tuple[np.ndarray, np.ndarray]:
    """(bin centre times, mean NE velocity per bin) of the track: the smoothing the jerk
    metric is defined with."""
    if len(track.t_s) < 2:
        return np.zeros(0), np.zeros((0, 2))
    idx = np.floor((track.t_s - track.t_s[0]) / bin_s).astype(int)
    n = idx[-1] + 1
    counts = np.bincount(idx, minlength=n)
    keep = counts > 0
    v = np.stack([np.bincount(idx, track.vel_ne[:, k], minlength=n) for k in (0, 1)], axis=1)
    t = track.t_s[0] + (np.arange(n) + 0.5) * bin_s
    return t[keep], v[keep] / counts[keep, None]


def accel_jerk(track: Track, bin_s: float = JERK_BIN_S) -> tuple[float, float]:
    """(largest horizontal acceleration [m/s^2], RMS horizontal jerk [m/s^3]) of the binned
    true velocity."""
    t, v = binned_velocity(track, bin_s)
    if len(t) < 3:
        return math.nan, math.nan
    a = np.diff(v, axis=0) / np.diff(t)[:, None]
    j = np.diff(a, axis=0) / np.diff(t[1:])[:, None]
    return float(np.linalg.norm(a, axis=1).max()), \
        float(np.sqrt(np.mean((j * j).sum(axis=1))))


def score_mission(track: Track, waypoints, t_start: float, t_budget_end: float,
                  start_ne=(0.0, 0.0)) -> dict:
    """N3/N4's row, from the AUTO start to the first true arrival within ARRIVE_M of the
    last waypoint: time to complete, cross-track RMS and maximum to the reference path
    (tools/benchmark/nav/spline.py), peak acceleration and RMS jerk. A mission never
    completed scores its cross-track up to t_budget_end and time NaN."""
    last = np.array([waypoints[-1].north_m, waypoints[-1].east_m])
    w = track.window(t_start, t_budget_end)
    # The last waypoint counts only once the vehicle has passed the one before it (within
    # PASS_M): the mission ends where it started, where the vehicle is before it leaves.
    before = np.array([waypoints[-2].north_m, waypoints[-2].east_m])
    near_before = np.flatnonzero(np.linalg.norm(w.pos_ne - before, axis=1) < PASS_M)
    done = math.nan
    if len(near_before):
        d = np.linalg.norm(w.pos_ne[near_before[0]:] - last, axis=1)
        hit = np.flatnonzero(d < ARRIVE_M)
        if len(hit):
            done = float(w.t_s[near_before[0] + hit[0]])
    w = track.window(t_start, done if math.isfinite(done) else t_budget_end)
    path, _ = reference_path(start_ne, waypoints)
    step = max(1, int(round(1.0 / (XTRACK_HZ * max(np.median(np.diff(w.t_s)), 1e-6)))))\
        if len(w.t_s) > 1 else 1
    xt = distance_to_path(path, w.pos_ne[::step]) if len(w.t_s) else np.zeros(0)
    accel_max, jerk_rms = accel_jerk(w)
    return {"time_s": done - t_start if math.isfinite(done) else math.nan,
            "xtrack_rms_m": float(np.sqrt(np.mean(xt * xt))) if len(xt) else math.nan,
            "xtrack_max_m": float(xt.max()) if len(xt) else math.nan,
            "accel_max_m_s2": accel_max, "jerk_rms_m_s3": jerk_rms}
