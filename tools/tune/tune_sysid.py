"""`silbridge tune sysid`: sweep one axis from a hover and read its loops.

Two flights per axis, each with the FC's SYSTEMID sweep (fc_sysid.h):
- "output": the sweep on the mixer input (SID_AXIS 10-12). Identified with the
  sweep d as instrument (tune_freq.py): the rate plant P = mixer input [us] ->
  true body rate [rad/s]; the loop broken at the plant input L = -u_ctrl / u
  (u = u_ctrl + d, u_ctrl = what the rate and attitude loops add); the input
  sensitivity 1 / (1 + L) = u / d and its complement -u_ctrl / d. The
  stability margins (gain, phase, delay) are L's: the loop opened where the
  controller meets the vehicle, attitude loop included.
- "input": the sweep on the rate-loop target (SID_AXIS 7-9): the closed rate
  loop T = target -> true rate, whose -3 dB point is the bandwidth, the rate
  sensitivity S = target -> rate error, and the rate loop L_r = error -> rate
  (reported as "rate_loop" margins).
The sweep, magnitudes and times are SID_* parameters, so the same numbers fly
on ArduCopter. Analysis keeps the samples while the sweep runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from silbridge.tools.tune import tune_defaults as D
from silbridge.tools.tune.tune_flight import CaptureSpec, FlightCapture, fly_captured
from silbridge.tools.tune.tune_freq import Frf, SweepSpectra, bandwidth_hz, margins

AXES = ("roll", "pitch", "yaw")
_AXIS_INDEX = {"roll": 0, "pitch": 1, "yaw": 2}
_COMP = "xyz"
_GT = {"roll": "gt_p", "pitch": "gt_q", "yaw": "gt_r"}
# SID_AXIS values per injection point (ArduCopter's numbering).
SID_AXIS = {"input": {"roll": 7, "pitch": 8, "yaw": 9},
            "output": {"roll": 10, "pitch": 11, "yaw": 12}}
INJECTIONS = ("output", "input")
COHERENCE_MIN = 0.9


class TuneError(Exception):
    user_facing = True


@dataclass(frozen=True)
class SweepConfig:
    """The sweep and the hover it starts from (defaults and their reasons:
    tune_defaults.py)."""
    f_start_hz: float = D.SWEEP_F_START_HZ
    f_stop_hz: float = D.SWEEP_F_STOP_HZ
    t_fade_in_s: float = D.SWEEP_T_FADE_IN_S
    t_rec_s: float = D.SWEEP_T_REC_S
    t_fade_out_s: float = 2.0            # ArduCopter's SID_T_FADE_OUT
    magnitude_rate_dps: float = D.SWEEP_MAGNITUDE_RATE_DPS
    magnitude_mixer: float = D.SWEEP_MAGNITUDE_MIXER
    sweep_at_s: float = 15.0             # hover established by then (S1 take-off)
    seed: int = 1
    scenario: str = "S1"

    def sid_params(self, axis: str, injection: str) -> dict:
        mag = self.magnitude_mixer if injection == "output" else self.magnitude_rate_dps
        return {"SID_AXIS": SID_AXIS[injection][axis], "SID_MAGNITUDE": mag,
                "SID_F_START_HZ": self.f_start_hz, "SID_F_STOP_HZ": self.f_stop_hz,
                "SID_T_FADE_IN": self.t_fade_in_s, "SID_T_REC": self.t_rec_s,
                "SID_T_FADE_OUT": self.t_fade_out_s}

    def duration_s(self) -> float:
        return self.sweep_at_s + 1.0 + self.t_rec_s + 0.5


def capture_spec(axis: str, injection: str, cfg: SweepConfig, params: dict | None = None
                 ) -> CaptureSpec:
    if axis not in AXES:
        raise TuneError(f"unknown axis {axis!r}: use roll, pitch or yaw")
    if injection not in INJECTIONS:
        raise TuneError(f"unknown injection {injection!r}: use output (mixer) or input (rate)")
    p = {**(params or {}), **cfg.sid_params(axis, injection)}
    return CaptureSpec(scenario=cfg.scenario, seed=cfg.seed, duration_s=cfg.duration_s(),
                       params=p, sweep_at_s=cfg.sweep_at_s,
                       capture_from_s=cfg.sweep_at_s - 0.5, label=f"{axis}/{injection}")


@dataclass
class AxisResult:
    axis: str
    frfs: dict = field(default_factory=dict)      # name -> Frf
    summary: dict = field(default_factory=dict)   # the --json figures


def _sweep_rows(cap: FlightCapture, axis: str, injection: str) -> dict:
    d = cap.data
    want = SID_AXIS[injection][axis]
    m = (d["active"] > 0.5) & (d["axis"] == want)
    if m.sum() < 1000:
        raise TuneError(f"{axis}/{injection}: the sweep ran for {int(m.sum())} steps only "
                        f"(it stops when the vehicle lands or tilts past ANGLE_MAX); "
                        f"lower the magnitude")
    return cap.window(m)


def _fs(rows: dict) -> float:
    return 1.0 / float(np.median(np.diff(rows["t"])))


def analyse_output(cap: FlightCapture, axis: str, cfg: SweepConfig, us_per_unit: float) -> dict:
    """The mixer-input sweep: plant, loop at the plant input, input sensitivities."""
    r = _sweep_rows(cap, axis, "output")
    c = _COMP[_AXIS_INDEX[axis]]
    d_us = r["sample"] * us_per_unit
    u = r[f"mixer_{c}"]
    u_ctrl = u - d_us               # rate/attitude loops' part (trim included: constant)
    sp = SweepSpectra(d_us, _fs(r), cfg.f_start_hz)
    du = sp.response(u)
    duc = sp.response(u_ctrl)
    loop = Frf(du.f_hz, -duc.h / du.h, np.minimum(du.coherence, duc.coherence))
    return {"plant": sp.transfer(u, r[_GT[axis]]),
            "plant_gyro": sp.transfer(u, r[f"rate_{c}"]),
            "open_loop": loop,
            "sensitivity_in": du,
            "complementary_in": Frf(duc.f_hz, -duc.h, duc.coherence)}


def analyse_input(cap: FlightCapture, axis: str, cfg: SweepConfig) -> dict:
    """The rate-target sweep: closed rate loop, its sensitivity and open rate loop."""
    r = _sweep_rows(cap, axis, "input")
    c = _COMP[_AXIS_INDEX[axis]]
    d = np.radians(r["sample"])
    target = r[f"rate_target_{c}"]
    meas = r[f"rate_{c}"]
    err = target - meas
    sp = SweepSpectra(d, _fs(r), cfg.f_start_hz)
    return {"closed_loop": sp.transfer(target, r[_GT[axis]]),
            "closed_loop_gyro": sp.transfer(target, meas),
            "sensitivity": sp.transfer(target, err),
            "rate_loop": sp.transfer(err, meas)}


def _in_band(frf: Frf, cfg: SweepConfig, coh_min: float = COHERENCE_MIN) -> Frf:
    m = ((frf.f_hz >= cfg.f_start_hz) & (frf.f_hz <= cfg.f_stop_hz)
         & np.isfinite(frf.h) & (np.abs(frf.h) > 0))
    sel = frf.select(m)
    # Margins need a continuous curve: keep the band up to the first incoherent stretch
    # above the lowest coherent point, so a phase is never unwrapped across noise.
    ok = sel.coherence >= coh_min
    if not ok.any():
        return sel.select(ok)
    first = int(np.argmax(ok))
    bad = np.nonzero(~ok[first:])[0]
    last = first + (int(bad[0]) if len(bad) else len(ok) - first)
    return sel.select(slice(first, last))


def gain_margin_bound(band: Frf, s: dict) -> float | None:
    """When the phase crossover lies above the coherent band: the gain margin is at least
    -|L| at the band's top, because beyond it |L| only falls (a strictly proper plant
    behind low-pass filters: the rigid body's -40 dB/decade outruns the D term's +20)
    while the phase keeps dropping. None when the band says nothing (or GM was found)."""
    if s.get("gain_margin_db") is not None or len(band.f_hz) < 2:
        return s.get("gain_margin_db")
    mag = 20.0 * np.log10(np.abs(band.h[-1]))
    if mag >= 0.0:
        return None
    return float(-mag)


def coherent_band(frf: Frf, cfg: SweepConfig) -> list | None:
    b = _in_band(frf, cfg)
    return [float(b.f_hz[0]), float(b.f_hz[-1])] if len(b.f_hz) else None


def summarise_axis(axis: str, out: dict | None, inp: dict | None, cfg: SweepConfig) -> AxisResult:
    res = AxisResult(axis=axis)
    s: dict = {"phase_margin_deg": None, "gain_margin_db": None, "crossover_hz": None,
               "bandwidth_hz": None, "delay_margin_ms": None, "phase_crossover_hz": None}
    if out is not None:
        res.frfs.update(out)
        band = _in_band(out["open_loop"], cfg)
        s.update(margins(band.f_hz, band.h))
        s["gain_margin_min_db"] = gain_margin_bound(band, s)
        s["open_loop_band_hz"] = coherent_band(out["open_loop"], cfg)
        s["plant_band_hz"] = coherent_band(out["plant"], cfg)
    if inp is not None:
        res.frfs.update(inp)
        cl = _in_band(inp["closed_loop"], cfg)
        s["bandwidth_hz"] = bandwidth_hz(cl.f_hz, cl.h) if len(cl.f_hz) else None
        rl = _in_band(inp["rate_loop"], cfg)
        s["rate_loop"] = margins(rl.f_hz, rl.h)
        s["closed_loop_band_hz"] = coherent_band(inp["closed_loop"], cfg)
    for k, v in list(s.items()):
        if isinstance(v, float) and not math.isfinite(v):
            s[k] = None
    res.summary = s
    return res


def us_per_unit(params: dict) -> float:
    """PWM us per normalised rate-loop unit: half the PWM range (fc_config_map.c)."""
    from silbridge.fc_sil.params import BY_NAME
    lo = params.get("MOT_PWM_MIN", BY_NAME["MOT_PWM_MIN"].default)
    hi = params.get("MOT_PWM_MAX", BY_NAME["MOT_PWM_MAX"].default)
    return 0.5 * (float(hi) - float(lo))


def sysid_task(task: tuple) -> tuple:
    """Executor task: (axis, injection, cfg, params) -> (key, analysed FRFs, crashed)."""
    axis, injection, cfg, params = task
    cap = fly_captured(capture_spec(axis, injection, cfg, params))
    if cap.crashed:
        raise TuneError(f"{axis}/{injection}: the vehicle crashed during the sweep; "
                        f"lower the magnitude or check the gains")
    if injection == "output":
        frfs = analyse_output(cap, axis, cfg, us_per_unit(params))
    else:
        frfs = analyse_input(cap, axis, cfg)
    return (axis, injection), frfs


def identify(axes, cfg: SweepConfig, params: dict | None = None, *, injections=INJECTIONS,
             runner=None) -> dict[str, AxisResult]:
    """Sweep each axis (one flight per injection point) and summarise it.
    runner(fn, tasks) -> results (default: in this process, one after another)."""
    params = dict(params or {})
    tasks = [(a, inj, cfg, params) for a in axes for inj in injections]
    results = runner(sysid_task, tasks) if runner else [sysid_task(t) for t in tasks]
    got = {key: frfs for key, frfs in results}
    return {a: summarise_axis(a, got.get((a, "output")), got.get((a, "input")), cfg)
            for a in axes}


def with_overrides(cfg: SweepConfig, **kw) -> SweepConfig:
    return replace(cfg, **{k: v for k, v in kw.items() if v is not None})
