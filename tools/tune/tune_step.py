"""`silbridge tune step`: step and doublet responses per axis, from a hover.

The flight is a scenario written on the fly: S1's hover at 10 m, then attitude
doublets (+A, level, -A, level, the scenario format's `tilt` setpoint) on roll
or pitch, or heading steps on yaw. Every edge of the command is a step; for
each, from the true attitude (ground truth) against the raw command:
  rise time   10 % -> 90 % of the step,
  overshoot   largest excursion past the new value, in % of the step,
  settling    last time the error leaves a +-5 % band of the step (from the edge),
and per doublet the RMS of (command - true) over the doublet.
Yaw steps need a heading loop: with ATC_ANG_YAW_P = 0 (rate damping only, the
default) the yaw run sets ATC_ANG_YAW_P = 4.5 (ArduCopter's default) and says so.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from silbridge.tools.tune import tune_defaults as D
from silbridge.tools.tune.tune_flight import CaptureSpec, fly_captured
from silbridge.tools.tune.tune_sysid import AXES, TuneError

SETTLE_BAND = 0.05
YAW_HOLD_P = 4.5


@dataclass(frozen=True)
class StepConfig:
    amplitude_deg: float = D.STEP_AMPLITUDE_DEG
    hold_s: float = D.STEP_HOLD_S
    repeat: int = D.STEP_REPEAT
    period_s: float = 8.0
    start_s: float = 15.0
    seed: int = 1

    def duration_s(self) -> float:
        return self.start_s + self.repeat * self.period_s + 1.0


def scenario_text(axis: str, cfg: StepConfig) -> str:
    head = (f'name = "tune-step-{axis}"\ndescription = "hover at 10 m, {axis} doublets"\n'
            f"seed = {cfg.seed}\nduration_s = {cfg.duration_s()}\ntakeoff_alt_m = 10.0\n")
    if axis in ("roll", "pitch"):
        return head + (f'\n[[setpoint]]\ntype = "tilt"\naxis = "{axis}"\nshape = "step"\n'
                       f"amplitude_deg = {cfg.amplitude_deg}\nhold_s = {cfg.hold_s}\n"
                       f"start_s = {cfg.start_s}\nrepeat = {cfg.repeat}\n"
                       f"period_s = {cfg.period_s}\n")
    lines = [head]
    for k in range(cfg.repeat):   # yaw: +A then back, per repetition (a heading doublet)
        t0 = cfg.start_s + k * cfg.period_s
        for t, yaw in ((t0, cfg.amplitude_deg), (t0 + cfg.hold_s * 2, 0.0)):
            lines.append(f'\n[[setpoint]]\ntype = "yaw"\nyaw_deg = {yaw}\nstart_s = {t}\n')
    return "".join(lines)


def edges(cmd: np.ndarray, min_jump: float) -> list[int]:
    """Indices where the command jumps by at least min_jump."""
    jumps = np.nonzero(np.abs(np.diff(cmd)) >= min_jump)[0] + 1
    return [int(i) for i in jumps]


def step_metrics(t, cmd, actual, i0: int, i1: int) -> dict:
    """One step at sample i0 (the command's new value held until i1)."""
    before = float(cmd[i0 - 1])
    after = float(cmd[i0])
    size = after - before
    tt = t[i0:i1] - t[i0]
    y = (actual[i0:i1] - before) / size        # 0 -> 1 normalised response
    out = {"from_deg": math.degrees(before), "to_deg": math.degrees(after),
           "rise_time_s": None, "overshoot_pct": None, "settling_time_s": None}
    if len(y) < 3:
        return out
    above10 = np.nonzero(y >= 0.1)[0]
    above90 = np.nonzero(y >= 0.9)[0]
    if len(above10) and len(above90):
        out["rise_time_s"] = float(tt[above90[0]] - tt[above10[0]])
    out["overshoot_pct"] = float(max(0.0, (y.max() - 1.0) * 100.0))
    outside = np.nonzero(np.abs(y - 1.0) > SETTLE_BAND)[0]
    if len(outside) == 0:
        out["settling_time_s"] = 0.0
    elif outside[-1] < len(y) - 1:
        out["settling_time_s"] = float(tt[outside[-1] + 1])
    return out


def _mean(rows, key):
    vals = [r[key] for r in rows if r.get(key) is not None]
    return float(np.mean(vals)) if vals else None


def analyse(data: dict, axis: str, cfg: StepConfig) -> dict:
    t = data["t"]
    if axis == "yaw":
        cmd = data["cmd_yaw"]
        actual = np.unwrap(data["gt_yaw"])
    else:
        cmd = data[f"cmd_{axis}"]
        actual = data[f"gt_{axis}"]
    idx = edges(cmd, math.radians(cfg.amplitude_deg) * 0.5)
    if not idx:
        raise TuneError(f"{axis}: no command step found in the flight")
    bounds = idx + [len(t)]
    steps = [step_metrics(t, cmd, actual, bounds[k], bounds[k + 1]) for k in range(len(idx))]
    first = [s for s in steps if abs(s["from_deg"]) < 1e-6]   # level -> +-A: the step response
    per = 2 if axis == "yaw" else 4
    doublets = []
    for k in range(0, len(idx), per):
        a = idx[k]
        b = idx[k + per] if k + per < len(idx) else len(t)
        b = min(b, a + int(cfg.period_s / max(np.median(np.diff(t)), 1e-6)))
        err = np.degrees(cmd[a:b] - actual[a:b])
        doublets.append({"start_s": float(t[a]), "rms_err_deg": float(np.sqrt(np.mean(err ** 2)))})
    return {"steps": steps,
            "step": {k: _mean(first, k) for k in ("rise_time_s", "overshoot_pct",
                                                   "settling_time_s")},
            "doublet": {**{k: _mean(steps, k) for k in ("rise_time_s", "overshoot_pct",
                                                        "settling_time_s")},
                        "rms_err_deg": _mean(doublets, "rms_err_deg")},
            "series": (t, cmd, actual, idx)}


def step_task(task: tuple) -> tuple:
    """Executor task: (axis, cfg, params, work_dir) -> (axis, analysis, note)."""
    axis, cfg, params, work_dir = task
    if axis not in AXES:
        raise TuneError(f"unknown axis {axis!r}: use roll, pitch or yaw")
    params = dict(params)
    note = ""
    if axis == "yaw" and float(params.get("ATC_ANG_YAW_P", 0.0)) <= 0.0:
        params["ATC_ANG_YAW_P"] = YAW_HOLD_P
        note = f"heading steps need a heading loop: flown with ATC_ANG_YAW_P = {YAW_HOLD_P}"
    with tempfile.TemporaryDirectory(dir=work_dir) as tmp:
        path = Path(tmp) / f"tune_step_{axis}.toml"
        path.write_text(scenario_text(axis, cfg))
        cap = fly_captured(CaptureSpec(scenario=str(path), seed=cfg.seed,
                                       duration_s=cfg.duration_s(), params=params,
                                       sweep_at_s=None, capture_from_s=cfg.start_s - 1.0))
    if cap.crashed:
        raise TuneError(f"{axis}: the vehicle crashed during the steps; check the gains")
    return axis, analyse(cap.data, axis, cfg), note
