"""The paper's metrics (section 4.5, Table 1), computed from a run log alone.

Time windows are in seconds of sim time (`Windows`): warm-up 0-10, transient
10-30, analysis 30-120, yaw 90-120 by default. A window is closed at both
ends. Every metric below uses the analysis window unless it says otherwise.

pwm_pp_us        PWM peak-to-peak: per motor, max - min of the PWM actually
                 published (/pwm pwm_us, the first channel_count channels);
                 the mean over motors. pwm_pp_max_us: the largest motor's.
sat_pct          Saturation occupancy: share of PWM samples in which any motor
                 has |u| >= 0.99, u = (pwm - mid) / half, mid and half from the
                 run's MOT_PWM_MIN/MOT_PWM_MAX parameters (1000/2000 us if not
                 logged), so u = +-1 at the PWM limits; in percent.
att_rms_deg      Attitude error against the scenario's command (the paper's
att_p95_deg      definition, Table 1's headline): the same as
att_max_deg      att_rms_cmd_deg, att_p95_cmd_deg, att_max_cmd_deg.
att_*_cmd_deg    At every FC status row, e = sqrt(droll^2 + dpitch^2), d =
att_*_target_deg reference - TRUE attitude (/gt_att); RMS, 95th percentile,
                 maximum, and per axis (att_rms_roll_*, att_rms_pitch_*).
                 cmd: the scenario's command (/setpoint); target: the FC's own
                 shaped target (/fc/target for an external FC, /fc/status
                 att_target_rad for ours). tools/benchmark/att_scoring.py says exactly how.
yaw_rate_rad_s   Steady yaw rate: mean TRUE body z rate (/gt_att
                 rates_frd_rad_s[2]) over the yaw window (90-120 s);
                 yaw_rate_abs_rad_s: mean of its magnitude.
cp_us, cr_us,    Mixer-input commands: mean of the FC status cp_us, cr_us,
cy_us            cy_us (offsets about the 1500 us centre, as the paper's
                 "cp ~ 0.77 us"); throttle_us: mean status throttle.
latency_ms       End-to-end latency: pwm_wall_ns - imu_wall_ns of the /timing
latency_p99_ms   rows that produced a PWM; median and 99th percentile.
                 sensor_latency_ms / _p99_ms: consume_wall_ns - imu_wall_ns.
jitter_ms        Loop jitter: |loop_period_ns - nominal| over /timing rows,
jitter_p50_ms    99th percentile and median; nominal = the median loop period
                 (reported as loop_period_ms), which is right both in real time
                 (where it is the pacing period) and in lockstep (where the
                 period is whatever the machine takes).
gyro_noise_dps   Noise: the RMS from 20 Hz to the log's Nyquist frequency of the
gyro_in_noise_dps FC's filtered gyro, of the sensor IMU, of the D terms and of
dterm_noise_us   each motor's PWM (tools/benchmark/noise.py says exactly how
motor_noise_us   and why).

Missing data gives NaN for the metrics that need it. When the log is shorter
than a window, the window is cut to the log, or (if nothing is left) replaced
by the part of the log after the warm-up (the whole log if it ends inside the
warm-up); `window_note` says what was used ("" when the windows were whole).
The windows used are reported as analysis_start_s ... yaw_end_s.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from silbridge.tools.benchmark.att_scoring import attitude_scores, roll_pitch_from_quat  # noqa: F401
from silbridge.tools.benchmark.noise import noise_metrics
from silbridge.tools.logs.mcap_log import RunLog

NAN = float("nan")
SAT_THRESHOLD = 0.99


@dataclasses.dataclass(frozen=True)
class Windows:
    warmup: tuple[float, float] = (0.0, 10.0)
    transient: tuple[float, float] = (10.0, 30.0)
    analysis: tuple[float, float] = (30.0, 120.0)
    yaw: tuple[float, float] = (90.0, 120.0)

    def __post_init__(self):
        for name in ("warmup", "transient", "analysis", "yaw"):
            a, b = getattr(self, name)
            if not b > a:
                raise ValueError(f"window {name} must end after it starts, got {a}..{b}")


def _resolve(win: tuple[float, float], name: str, log_end_s: float, warmup_end_s: float,
             notes: list[str]) -> tuple[float, float]:
    a, b = win
    if log_end_s >= b:
        return a, b
    if log_end_s > a:
        notes.append(f"{name} window {a:g}-{b:g} s cut to {a:g}-{log_end_s:.3f} s "
                     "(the log ends there)")
        return a, log_end_s
    start = warmup_end_s if log_end_s > warmup_end_s else 0.0
    notes.append(f"log ends at {log_end_s:.3f} s, before the {name} window {a:g}-{b:g} s: "
                 f"used {start:g}-{log_end_s:.3f} s")
    return start, log_end_s


def _select(log: RunLog, channel: str, win: tuple[float, float]) -> np.ndarray | None:
    rows = log.channels.get(channel)
    if rows is None:
        return None
    t = rows["sim_ns"]
    lo = np.searchsorted(t, int(round(win[0] * 1e9)), side="left")
    hi = np.searchsorted(t, int(round(win[1] * 1e9)), side="right")
    return rows[lo:hi]


def _pwm_limits_us(log: RunLog) -> tuple[float, float]:
    params = log.metadata.get("params") or {}
    lo = float(params.get("MOT_PWM_MIN", 1000) or 1000)
    hi = float(params.get("MOT_PWM_MAX", 2000) or 2000)
    return lo, hi


def _pwm_metrics(log: RunLog, win) -> dict:
    pwm = _select(log, "/pwm", win)
    out = {"pwm_pp_us": NAN, "pwm_pp_max_us": NAN, "sat_pct": NAN}
    if pwm is None or not len(pwm):
        return out
    nch = int(pwm["channel_count"].max()) if "channel_count" in pwm.dtype.names else 4
    us = pwm["pwm_us"][:, :max(nch, 1)].astype(np.float64)
    pp = us.max(axis=0) - us.min(axis=0)
    lo, hi = _pwm_limits_us(log)
    u = (us - (lo + hi) / 2.0) / ((hi - lo) / 2.0)
    saturated = np.any(np.abs(u) >= SAT_THRESHOLD, axis=1)
    out.update(pwm_pp_us=float(pp.mean()), pwm_pp_max_us=float(pp.max()),
               sat_pct=100.0 * float(saturated.mean()))
    return out


def _attitude_metrics(log: RunLog, win) -> dict:
    out = attitude_scores(log, _select(log, "/fc/status", win))
    # The headline (Table 1, the paper): against the command.
    for k in ("rms", "p95", "max", "rms_roll", "rms_pitch"):
        out[f"att_{k}_deg"] = out[f"att_{k}_cmd_deg"]
    return out


def _yaw_metrics(log: RunLog, win) -> dict:
    gt = _select(log, "/gt_att", win)
    if gt is None or not len(gt):
        return {"yaw_rate_rad_s": NAN, "yaw_rate_abs_rad_s": NAN}
    r = gt["rates_frd_rad_s"][:, 2].astype(np.float64)
    return {"yaw_rate_rad_s": float(r.mean()), "yaw_rate_abs_rad_s": float(np.abs(r).mean())}


def _mixer_metrics(log: RunLog, win) -> dict:
    st = _select(log, "/fc/status", win)
    out = {}
    for key in ("cp_us", "cr_us", "cy_us", "throttle_us"):
        ok = st is not None and len(st) and key in st.dtype.names
        out[key] = float(st[key].astype(np.float64).mean()) if ok else NAN
    return out


def _timing_metrics(log: RunLog, win) -> dict:
    out = {k: NAN for k in ("latency_ms", "latency_p99_ms", "sensor_latency_ms",
                            "sensor_latency_p99_ms", "jitter_ms", "jitter_p50_ms",
                            "loop_period_ms")}
    tim = _select(log, "/timing", win)
    if tim is None or not len(tim):
        return out
    produced = tim[tim["pwm_wall_ns"] > 0]
    if len(produced):
        e2e = (produced["pwm_wall_ns"] - produced["imu_wall_ns"]) * 1e-6
        out.update(latency_ms=float(np.median(e2e)), latency_p99_ms=float(np.percentile(e2e, 99)))
    sens = (tim["consume_wall_ns"] - tim["imu_wall_ns"]) * 1e-6
    out.update(sensor_latency_ms=float(np.median(sens)),
               sensor_latency_p99_ms=float(np.percentile(sens, 99)))
    period = tim["loop_period_ns"][tim["loop_period_ns"] > 0] * 1e-6
    if len(period):
        nominal = float(np.median(period))
        dev = np.abs(period - nominal)
        out.update(loop_period_ms=nominal, jitter_ms=float(np.percentile(dev, 99)),
                   jitter_p50_ms=float(np.median(dev)))
    return out


def compute_metrics(log: RunLog, windows: Windows = Windows()) -> dict:
    """Every metric of the module docstring, as floats, plus `window_note` (str)."""
    notes: list[str] = []
    end_s = log.duration_s()
    analysis = _resolve(windows.analysis, "analysis", end_s, windows.warmup[1], notes)
    if end_s > windows.yaw[0]:
        yaw = _resolve(windows.yaw, "yaw", end_s, windows.warmup[1], notes)
    else:
        yaw = analysis
        notes.append(f"log ends before the yaw window {windows.yaw[0]:g}-{windows.yaw[1]:g} s: "
                     "yaw rate over the analysis window used")
    out: dict = {}
    out.update(_pwm_metrics(log, analysis))
    out.update(_attitude_metrics(log, analysis))
    out.update(_yaw_metrics(log, yaw))
    out.update(_mixer_metrics(log, analysis))
    out.update(_timing_metrics(log, analysis))
    out.update(noise_metrics(log, analysis))
    out.update(analysis_start_s=float(analysis[0]), analysis_end_s=float(analysis[1]),
               yaw_start_s=float(yaw[0]), yaw_end_s=float(yaw[1]), log_end_s=float(end_s),
               window_note="; ".join(notes))
    return out


def json_safe(metrics: dict) -> dict:
    """NaN and infinities as None, for strict JSON."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in metrics.items()}
