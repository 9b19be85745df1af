"""A failure run's row: what the autopilot did (its timeline, watch.py) and what the vehicle
did (the bridge's ground truth, never the autopilot's telemetry). Pure functions of those.

- detection: the first alert text (severity WARNING or worse) or failsafe mode change from
  the fault's start to DETECT_GRACE_S after its end; the time from the fault's start. Our
  FC's echo of the injection itself ("Failure injected: rc lost", fc_sil/fault_inject.py,
  for the FC-side units a scenario switches) is not a detection.
- action: the first mode change in that window (or a disarm in the air), by name: LAND,
  RTL, ALT_HOLD ...; none. A mission that ends by itself into a hold at its last waypoint
  (PX4 switches to Hold there) is the mission ending, not an action.
- outcome: crashed (the ground met faster than CRASH_M_S, or the vehicle ended tilted past
  UPSET_DEG), landed upright (on the ground, slower than REST_M_S, tilt below UPSET_DEG),
  else still flying.
- deviations, from the true position at the fault's start: hold: the horizontal distance
  to it over the whole fault, the vertical one until the autopilot acted (a LAND or RTL
  then moves the vehicle on purpose); mission: the distance to the mission's path and to
  its height, until the autopilot acted or the fault ended.
- landing distance: after an RTL from home, otherwise from the point where the fault hit.
- disarm: the first disarm after the fault, "on the ground" or "in the air" (higher than
  GROUND_M), or "none", and its time from the fault: a crash check disarms on the ground
  after the impact (F12), a landing's disarm follows the touchdown.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from silbridge.tools.benchmark.failures.plans import ALT_M, MISSION_NE
from silbridge.tools.benchmark.failures.watch import ALERT_SEVERITY

# Texts that are not the autopilot detecting anything: our FC echoing an injection
# (fc_sil/fault_inject.py) and the simulator's own notices ("SIM: IMU 900<1000Hz ...",
# fc_sil/sim_notice.py), which a link fault's dropped records trigger by design.
NOT_DETECTIONS = ("Failure injected:", "Failure cleared:", "SIM: ")
DETECT_GRACE_S = 10.0    # a failsafe with its own timer may act this long after the fault
GROUND_M = 0.5           # below this height above home the vehicle is on the ground [m]
CRASH_M_S = 3.0          # meeting the ground faster than this is a crash [m/s]
REST_M_S = 0.5           # landed: slower than this at the end [m/s]
UPSET_DEG = 45.0         # tilted past this at the end: on its side, crashed [deg]
IN_PHASE_M = 2.0         # at the fault the vehicle flies within this of ALT_M [m]
MISSION_END_M = 3.0      # a hold this close to the mission's last waypoint ends the mission

# ArduCopter 4.6's custom modes (our FC uses the same numbers).
COPTER_MODES = {0: "STABILIZE", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 5: "LOITER", 6: "RTL",
                9: "LAND", 16: "POSHOLD", 17: "BRAKE", 21: "SMART_RTL"}
# PX4's main modes and AUTO's sub-modes (px4_custom_mode.h), named as ArduCopter's where they
# do the same thing, so the action column reads alike.
PX4_MAIN = {1: "MANUAL", 2: "ALT_HOLD", 3: "POSCTL", 5: "ACRO", 6: "OFFBOARD", 7: "STABILIZED"}
PX4_AUTO = {1: "READY", 2: "TAKEOFF", 3: "HOLD", 4: "AUTO", 5: "RTL", 6: "LAND", 8: "FOLLOW",
            9: "PRECLAND"}
FAILSAFE_MODES = {"LAND", "RTL", "ALT_HOLD", "SMART_RTL", "STABILIZE", "STABILIZED", "MANUAL"}


@dataclass
class Truth:
    """The true state per physics step: t [s], NE [m], height above home [m], NED velocity
    [m/s], tilt [deg]."""
    t_s: np.ndarray
    ne: np.ndarray
    alt: np.ndarray
    vel: np.ndarray
    tilt_deg: np.ndarray

    def at(self, t: float) -> int:
        return int(min(np.searchsorted(self.t_s, t), len(self.t_s) - 1))


def load_truth(log_path: str) -> Truth:
    from silbridge.tools.logs.log_reader import read_log
    log = read_log(log_path, channels=["/gt_nav", "/gt_att"])
    nav, att = log.channels.get("/gt_nav"), log.channels.get("/gt_att")
    if nav is None or att is None or not len(nav):
        raise ValueError(f"{log_path}: no ground truth (/gt_nav, /gt_att) in the log")
    n = min(len(nav), len(att))
    if (np.diff(nav["sim_ns"][:n].astype(np.int64)) <= 0).any():
        raise ValueError(f"{log_path}: the physics restarted in this run (the autopilot's "
                         f"SITL restarted): not one flight")
    pos = nav["pos_ned_m"][:n].astype(float)
    q = att["q_wxyz"][:n].astype(float)
    # Tilt: the angle between body down and earth down, from the quaternion's (3,3) entry.
    c33 = 1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2)
    return Truth(nav["sim_ns"][:n] * 1e-9, pos[:, :2], -pos[:, 2],
                 nav["vel_ned_m_s"][:n].astype(float),
                 np.degrees(np.arccos(np.clip(c33, -1.0, 1.0))))


def mode_name(fc: str, custom_mode) -> str:
    if custom_mode is None:
        return "?"
    if fc == "px4":
        main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
        return PX4_AUTO.get(sub, f"AUTO.{sub}") if main == 4 else PX4_MAIN.get(main, str(main))
    return COPTER_MODES.get(custom_mode, str(custom_mode))


def first_action(fc: str, timeline, on_s: float, until_s: float, truth: Truth, phase: str):
    """(t_s, name) of the first mode change or in-air disarm in [on_s, until_s), or None.
    A hold that leads into a failsafe mode within the window (PX4 holds COM_FAIL_ACT_T
    before it acts) is named with it, "HOLD>RTL", at the hold's time."""
    first = _changes(fc, timeline, on_s, until_s, truth, phase)
    if not first:
        return None
    t, name = first[0]
    if name in ("HOLD", "BRAKE"):
        then = next((n for _, n in first[1:] if n in FAILSAFE_MODES), None)
        if then is not None:
            return t, f"{name}>{then}"
    return t, name


def _changes(fc: str, timeline, on_s: float, until_s: float, truth: Truth, phase: str) -> list:
    """(t_s, name) of every mode change or in-air disarm in [on_s, until_s)."""
    out = []
    before = [m for m in timeline.modes if m[0] < on_s]
    last = mode_name(fc, before[-1][1]) if before else None
    for t, mode, armed in timeline.modes:
        if not on_s <= t < until_s:
            continue
        if not armed:
            if truth.alt[truth.at(t)] > GROUND_M:
                out.append((t, "disarm"))
            continue
        name = mode_name(fc, mode)
        if name == last:
            continue
        last = name
        if phase == "mission" and name in ("HOLD", "LOITER", "BRAKE") and \
                math.hypot(*(truth.ne[truth.at(t)] - MISSION_NE[-1])) < MISSION_END_M:
            continue
        out.append((t, name))
    return out


def disarm_time(timeline, on_s: float) -> float:
    """Sim time of the first disarm after the fault (the run's whole remainder), or nan."""
    return next((t for t, _, armed in timeline.modes if t >= on_s and not armed), math.nan)


def disarm(timeline, on_s: float, truth: Truth) -> str:
    """Where the first disarm after the fault happened."""
    t = disarm_time(timeline, on_s)
    if math.isnan(t):
        return "none"
    return "in the air" if truth.alt[truth.at(t)] > GROUND_M else "on the ground"


def detection(fc: str, timeline, on_s: float, until_s: float, action) -> tuple:
    """(seconds from the fault, what said it) of the first alert or action, or (nan, "")."""
    alert = next(((t, text) for t, sev, text in timeline.texts
                  if on_s <= t < until_s and sev <= ALERT_SEVERITY
                  and not text.startswith(NOT_DETECTIONS)), None)
    hits = [h for h in (alert, action) if h is not None]
    if not hits:
        return math.nan, ""
    t, what = min(hits, key=lambda h: h[0])
    return t - on_s, what


def outcome(truth: Truth, on_s: float) -> str:
    after = truth.t_s >= on_s
    ground = after & (truth.alt < GROUND_M)
    if ground.any():
        speed = np.linalg.norm(truth.vel[ground], axis=1)
        # The ground met fast: the first sample on the ground of each arrival.
        arrivals = np.flatnonzero(np.diff(np.r_[False, ground]) > 0)
        if (np.linalg.norm(truth.vel[arrivals], axis=1) > CRASH_M_S).any() or \
                speed.max(initial=0.0) > 3.0 * CRASH_M_S:
            return "crashed"
    if truth.tilt_deg[-1] > UPSET_DEG:
        return "crashed"
    if truth.alt[-1] < GROUND_M:
        return "landed upright" if np.linalg.norm(truth.vel[-1]) < REST_M_S else "crashed"
    return "still flying"


def _path_distance(ne: np.ndarray) -> np.ndarray:
    from silbridge.tools.benchmark.nav.spline import distance_to_path
    pts = np.array([(0.0, 0.0)] + list(MISSION_NE))
    dense = np.concatenate([np.linspace(a, b, 200, endpoint=False) for a, b in
                            zip(pts[:-1], pts[1:])] + [pts[-1:]])
    return distance_to_path(dense, ne)


def score(fc: str, plan, flight, truth: Truth) -> dict:
    """The run's row (plan: FailurePlan; flight: FailureFlight) or {"not_in_phase": why}."""
    on, off = plan.fault_on_s, plan.fault_off_s
    i0 = truth.at(on)
    if truth.t_s[-1] < on or abs(truth.alt[i0] - ALT_M) > IN_PHASE_M:
        return {"not_in_phase": f"at the fault ({on:g} s) the vehicle was "
                                f"{truth.alt[i0]:.1f} m high, not flying the phase at "
                                f"{ALT_M:g} m"}
    until = off + DETECT_GRACE_S
    tl = flight.timeline
    action = first_action(fc, tl, on, until, truth, plan.phase)
    detect_s, detect_by = detection(fc, tl, on, until, action)
    acted = action[0] if action else math.inf
    w = (truth.t_s >= on) & (truth.t_s < min(off, acted))
    held_ne, held_alt = truth.ne[i0], truth.alt[i0]
    if plan.phase == "hold":
        whole = (truth.t_s >= on) & (truth.t_s < off)
        dev_h = float(np.linalg.norm(truth.ne[whole] - held_ne, axis=1).max(initial=0.0))
        dev_v = float(np.abs(truth.alt[w] - held_alt).max(initial=0.0))
    else:
        dev_h = float(_path_distance(truth.ne[w][::20]).max(initial=0.0)) if w.any() else 0.0
        dev_v = float(np.abs(truth.alt[w] - ALT_M).max(initial=0.0))
    out = outcome(truth, on)
    name = action[1] if action else "none"
    home = name.split(">")[-1] in ("RTL", "SMART_RTL")
    expected = (0.0, 0.0) if home else tuple(held_ne)
    land = float(math.hypot(*(truth.ne[-1] - expected))) if out == "landed upright" \
        else math.nan
    volts_before = [v for t, v in tl.volts if t < on]
    volts_after = [v for t, v in tl.volts if t >= on]
    return {"detect_s": detect_s, "detected_by": detect_by, "action": name,
            "action_s": (action[0] - on) if action else math.nan, "outcome": out,
            "disarm": disarm(tl, on, truth), "disarm_s": disarm_time(tl, on) - on,
            "dev_h_m": dev_h, "dev_v_m": dev_v, "land_dist_m": land,
            "land_expected": "home" if home else "fault point",
            "volts_at_fault": volts_before[-1] if volts_before else math.nan,
            "volts_min_after": min(volts_after) if volts_after else math.nan}
