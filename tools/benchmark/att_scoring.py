"""Attitude error, scored two ways from a run log alone, for any FC.

At every /fc/status row (one per PWM tick or servo packet) in the window,
e = sqrt(droll^2 + dpitch^2), d = reference - TRUE attitude (ZYX Euler of the
latest /gt_att quaternion at or before the row), wrapped to +-180 deg; yaw is
excluded (rate-damped, no heading target). Two references
(tools/logs/fc_target.py says where each is logged):

- cmd: the scenario's command, the latest `/setpoint` record with a valid
  attitude at or before the row (records before the window count). The
  paper's definition and Table 1's headline: an FC that shapes its input
  pays for the shaping lag here. Logs without /setpoint fall back to
  /fc/status att_target_rad (older logs).
- target: the FC's own shaped target. `/fc/target` (an external FC's reports,
  placed on the physics clock by their own stamps, linearly interpolated
  between reports; NaN before the first), else, for our FC, /fc/status
  att_target_rad (its shaped target at that tick); NaN for an external FC's
  log without /fc/target (metadata config "fc" names the FC).

Keys: att_{rms,p95,max}_{cmd,target}_deg, att_rms_{roll,pitch}_{cmd,target}_deg.
"""

from __future__ import annotations

import numpy as np

from silbridge.tools.logs.fc_target import COMMAND_CHANNEL, MASK_ATTITUDE, TARGET_CHANNEL

NAN = float("nan")
SCORINGS = ("cmd", "target")


def roll_pitch_from_quat(q_wxyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ZYX Euler roll and pitch [rad] of body-to-NED quaternions (w, x, y, z)."""
    q = q_wxyz.astype(np.float64)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    return roll, pitch


def _wrap_rad(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def command_at(log, t_ns: np.ndarray, status) -> np.ndarray | None:
    """(n, 2) commanded roll, pitch [rad] at times t_ns."""
    sp = log.channels.get(COMMAND_CHANNEL)
    if sp is not None and len(sp):
        sp = sp[(sp["mask"] & MASK_ATTITUDE) != 0]
    if sp is None or not len(sp):
        return None if status is None else status["att_target_rad"][:, :2].astype(np.float64)
    idx = np.searchsorted(sp["sim_ns"], t_ns, side="right") - 1
    out = np.column_stack([sp["roll_rad"], sp["pitch_rad"]]).astype(np.float64)[
        np.clip(idx, 0, len(sp) - 1)]
    out[idx < 0] = np.nan     # before the first command: not scored
    return out


def target_at(log, t_ns: np.ndarray, status) -> np.ndarray | None:
    """(n, 2) the FC's own roll, pitch target [rad] at times t_ns."""
    tg = log.channels.get(TARGET_CHANNEL)
    if tg is None or not len(tg):
        if status is None or external_fc(log):   # its status holds no target of its own
            return None
        return status["att_target_rad"][:, :2].astype(np.float64)
    fc_ns = tg["fc_time_ns"].astype(np.int64)
    offset = int(np.min(tg["sim_ns"].astype(np.int64) - fc_ns))
    order = np.argsort(fc_ns, kind="stable")
    t_rep = (fc_ns[order] + offset).astype(np.float64)
    att = tg["att_target_rad"][order].astype(np.float64)
    t = t_ns.astype(np.float64)
    out = np.column_stack([np.interp(t, t_rep, att[:, 0]), np.interp(t, t_rep, att[:, 1])])
    out[t < t_rep[0]] = np.nan
    return out


def external_fc(log) -> bool:
    """True for a log of an autopilot other than ours (its metadata config names it)."""
    fc = (log.metadata.get("config") or {}).get("fc")
    return fc not in (None, "", "ours")


def target_clock_offset_ns(log) -> int | None:
    """The constant that maps /fc/target fc_time_ns onto the log clock (None: no channel)."""
    tg = log.channels.get(TARGET_CHANNEL)
    if tg is None or not len(tg):
        return None
    return int(np.min(tg["sim_ns"].astype(np.int64) - tg["fc_time_ns"].astype(np.int64)))


def _errors(ref: np.ndarray, roll: np.ndarray, pitch: np.ndarray, suffix: str) -> dict:
    keys = [f"att_{k}_{suffix}_deg" for k in ("rms", "p95", "max", "rms_roll", "rms_pitch")]
    ok = np.isfinite(ref).all(axis=1)
    if not ok.any():
        return dict.fromkeys(keys, NAN)
    d_roll = np.rad2deg(_wrap_rad(ref[ok, 0] - roll[ok]))
    d_pitch = np.rad2deg(_wrap_rad(ref[ok, 1] - pitch[ok]))
    e = np.hypot(d_roll, d_pitch)
    vals = (np.sqrt(np.mean(e * e)), np.percentile(e, 95), e.max(),
            np.sqrt(np.mean(d_roll ** 2)), np.sqrt(np.mean(d_pitch ** 2)))
    return {k: float(v) for k, v in zip(keys, vals)}


def attitude_scores(log, status) -> dict:
    """Both scorings over the status rows given (already cut to the window)."""
    out = {}
    gt = log.channels.get("/gt_att")
    if status is None or not len(status) or gt is None or not len(gt):
        for s in SCORINGS:
            out.update(_errors(np.full((1, 2), np.nan), np.zeros(1), np.zeros(1), s))
        return out
    t = status["sim_ns"]
    # The latest truth sample at or before each status time (the first if none is).
    idx = np.clip(np.searchsorted(gt["sim_ns"], t, side="right") - 1, 0, len(gt) - 1)
    roll, pitch = roll_pitch_from_quat(gt["q_wxyz"][idx])
    for s, ref in (("cmd", command_at(log, t, status)), ("target", target_at(log, t, status))):
        if ref is None:
            ref = np.full((len(t), 2), np.nan)
        out.update(_errors(ref, roll, pitch, s))
    return out
