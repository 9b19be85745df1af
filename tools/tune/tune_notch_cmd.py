"""`silbridge tune notch [LOG]`: read a hover's gyro spectrum, propose the harmonic
notch and gyro filter, write them as a .parm, fly them and compare.

The "before" is a log: the one given, or a fresh lockstep flight of --scenario (with
--params/--param). The "after" flies the same scenario, seed, duration and IMU rate,
with the parameters the "before" flew with, then --params/--param, then the proposal.
Both are judged by the gyro noise after filtering over the same window
(tools/tune/tune_notch_log.py says how it is measured). Flights stay in this process
(`fly --processes 1`, lockstep), so their figures do not depend on the machine's load.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from silbridge.fc_sil import params as P
from silbridge.tools.tune.tune_notch_filters import NotchDesign, chain_response, phase_lag_deg
from silbridge.tools.tune.tune_notch_log import (CHANNELS, evidence, filtered_gyro_noise,
                                                 flown_param, hover_window)
from silbridge.tools.tune.tune_notch_propose import predicted_rms, propose
from silbridge.tools.tune.tune_sysid import TuneError

TARGET_DB = -10.0       # issue 27: tune notch lowers V2's filtered gyro noise >= 10 dB


def declared_default(name: str) -> float:
    """A parameter's declared default; an FC without it cannot take the proposal."""
    d = P.BY_NAME.get(name)
    if d is None:
        raise TuneError(f"this FC core declares no {name} (fc_sil/core/fc_params.def): the "
                        "harmonic notch is not built in; update silbridge")
    return d.default


def check_declared(values: dict) -> None:
    missing = [n for n in values if n not in P.BY_NAME]
    if missing:
        raise TuneError(f"this FC core declares no {', '.join(missing)} "
                        "(fc_sil/core/fc_params.def): the harmonic notch is not built in; "
                        "update silbridge")


def flown_changes(log) -> dict:
    """The C-core parameters the log's flight had away from their defaults."""
    out = {}
    for name, value in (log.metadata.get("params") or {}).items():
        d = P.BY_NAME.get(name)
        if d is not None and not d.host and d.validate(d.default) != float(value):
            out[name] = value
    return out


def fly_logged(scenario: str, seed, duration_s, imu_hz, params: dict, log_path: Path,
               label: str) -> None:
    """One lockstep flight in this process, logged; a crash stops the tool."""
    from silbridge.tools.loop.flight import FlightOptions, fly_one_process

    log_path.parent.mkdir(parents=True, exist_ok=True)
    opts = FlightOptions(scenario=scenario, duration_s=duration_s, lockstep=True,
                         processes=1, seed=seed, imu_hz=imu_hz, log_path=str(log_path),
                         params=dict(params), viz_hz=0,
                         instance=f"tune-notch-{os.getpid()}-{label}")
    summary = fly_one_process(opts, out=lambda _line: None)
    if summary["crashed"]:
        raise TuneError(f"the {label} flight of {scenario} crashed (log {log_path}); "
                        "check the parameters it flew with")


def _flight_of(log) -> dict:
    """Scenario (its file when it still exists, else its name), seed, duration, IMU rate."""
    sc = log.metadata.get("scenario") or {}
    cfg = log.metadata.get("config") or {}
    src = sc.get("source")
    scenario = src if src and Path(src).is_file() else sc.get("name")
    if not scenario:
        raise TuneError(f"{log.path} does not say which scenario it flew; pass the log "
                        "of a silbridge flight, or --scenario instead of a log")
    note = "" if scenario == src else f"{src} is gone: flying the scenario named {scenario}"
    return {"scenario": scenario, "seed": cfg.get("seed"),
            "duration_s": cfg.get("duration_s") or log.duration_s(),
            "imu_hz": cfg.get("imu_hz"), "note": note}


def _db(after: float, before: float) -> float | None:
    return 20.0 * math.log10(after / before) if after > 0 and before > 0 else None


def _predicted(sp, prop, ev, band_hz, flown_notch) -> dict:
    """Filtered noise predicted from the raw spectrum: before (the flown low-pass and
    notch, the notch at its FREQ) and after (the proposal's notch at its hover centre
    and its low-pass)."""
    band = (band_hz[0], min(band_hz[1], sp.freq_hz[-1]))
    b = predicted_rms(sp.freq_hz, sp.psd, chain_response(sp.freq_hz, flown_notch,
                                                         ev.gyro_filter_hz, sp.rate_hz), band)
    a = predicted_rms(sp.freq_hz, sp.psd, chain_response(
        sp.freq_hz, prop.design, prop.values["INS_GYRO_FILTER"], sp.rate_hz), band)
    tb, ta = (float(np.degrees(np.linalg.norm(v))) for v in (b, a))
    return {"before_total_dps": tb, "after_total_dps": ta, "change_db": _db(ta, tb)}


def _phase(prop, ev, crossover_hz, flown_notch) -> dict | None:
    """The gyro filters' phase lag at the loop's crossover, flown and proposed."""
    if crossover_hz is None:
        return None
    return {"crossover_hz": crossover_hz,
            "before_deg": phase_lag_deg(crossover_hz, flown_notch, ev.gyro_filter_hz,
                                        ev.imu_rate_hz),
            "after_deg": phase_lag_deg(crossover_hz, prop.design,
                                       prop.values["INS_GYRO_FILTER"], ev.imu_rate_hz)}


def _flown_notch(log) -> NotchDesign | None:
    """The notch the log flew with, held at its FREQ (None when it was off)."""
    if not flown_param(log, "INS_HNTCH_ENABLE"):
        return None
    return NotchDesign(center_hz=flown_param(log, "INS_HNTCH_FREQ"),
                       bw_hz=flown_param(log, "INS_HNTCH_BW"),
                       att_db=flown_param(log, "INS_HNTCH_ATT"),
                       harmonics=int(flown_param(log, "INS_HNTCH_HMNCS")))


def _source(args, base: dict, out_dir: Path, say) -> tuple[Path, bool]:
    """(the "before" log, whether this run flew it)."""
    if args.log:
        if not Path(args.log).is_file():
            raise TuneError(f"{args.log}: no such log; give a `silbridge fly --log` file, "
                            "or --scenario NAME for a fresh hover")
        return Path(args.log), False
    path = out_dir / "before.mcap"
    say(f"flying {args.scenario} (seed {args.seed}) with the current parameters ...")
    fly_logged(args.scenario, args.seed, args.duration, None, base, path, "before")
    return path, True


def run_notch(args, base: dict, out_dir: Path, say) -> dict:
    from silbridge.tools.logs.log_reader import read_log
    from silbridge.tools.tune.tune_parm import write_parm

    out_dir.mkdir(parents=True, exist_ok=True)
    src, flew = _source(args, base, out_dir, say)
    log = read_log(src, channels=CHANNELS)
    window = hover_window(log, tuple(args.window) if args.window else None)
    ev, sp = evidence(log, window)
    prop = propose(ev, declared_default("INS_HNTCH_ATT"), args.mode)
    check_declared(prop.values)
    parm = write_parm(out_dir / "notch.parm", prop.values,
                      header=f"silbridge tune notch, from {src} ({window[0]:g}-{window[1]:g} s)")
    flight = _flight_of(log)
    if flight["note"]:
        say(f"note: {flight['note']}")
    params = {**flown_changes(log), **base, **prop.values}
    after_path = out_dir / "after.mcap"
    say(f"flying {Path(str(flight['scenario'])).stem} (seed {flight['seed']}, "
        f"{flight['duration_s']:g} s) with {parm} ...")
    fly_logged(flight["scenario"], flight["seed"], flight["duration_s"], flight["imu_hz"],
               params, after_path, "after")
    flown = _flown_notch(log)
    before = filtered_gyro_noise(log, window)
    after = filtered_gyro_noise(read_log(after_path, channels=CHANNELS), window)
    change = _db(after["total_dps"], before["total_dps"])
    result = {
        "source_log": str(src), "flew_source": flew, "after_log": str(after_path),
        "flight": flight, "window_s": [window[0], window[1]], "window_note": window[2],
        "evidence": _evidence_dict(ev), "proposal": prop.values, "reasons": prop.reasons,
        "parm_file": str(parm),
        "noise": {"measure": "gyro_noise_dps (tools/benchmark/noise.py): band RMS of "
                             "/fc/status rate_frd_rad_s, root sum square of the axes",
                  "band_hz": before["band_hz"], "before": before, "after": after,
                  "change_db": change, "target_db": TARGET_DB,
                  "met": change is not None and change <= TARGET_DB},
        "predicted": _predicted(sp, prop, ev, before["band_hz"], flown),
        "phase_lag": _phase(prop, ev, args.crossover_hz, flown),
    }
    _print(result, say)
    (out_dir / "summary.json").write_text(json.dumps(_finite(result), indent=1))
    return result


def _finite(v):
    """JSON without NaN or inf (they become null)."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_finite(x) for x in v]
    return v


def _evidence_dict(ev) -> dict:
    d = {k: getattr(ev, k) for k in ("imu_rate_hz", "fundamental_hz", "fundamental_source",
                                     "spread_hz", "lowest_hz", "hover_throttle", "esc",
                                     "gyro_filter_hz")}
    d["lines"] = [{"harmonic": ln.harmonic, "freq_hz": ln.freq_hz, "amp_rad_s": ln.amp_rad_s}
                  for ln in ev.lines]
    return d


def _print(r: dict, say) -> None:
    ev = r["evidence"]
    a, b = r["window_s"]
    say(f"{r['source_log']}: hover {a:g}-{b:g} s, rotor {ev['fundamental_hz']:.1f} Hz "
        f"({ev['fundamental_source']}), hover throttle {ev['hover_throttle']:.3f}, "
        f"ESC telemetry {'yes' if ev['esc'] else 'no'}")
    say("  gyro lines: " + ", ".join(f"{ln['harmonic']}x {ln['freq_hz']:.1f} Hz "
                                     f"{ln['amp_rad_s']:.3g} rad/s" for ln in ev["lines"]))
    for name, value in r["proposal"].items():
        say(f"  {name:<17} {value:<8g} {r['reasons'][name]}")
    n = r["noise"]
    lo, hi = n["band_hz"]
    say(f"gyro noise after filtering, RMS {lo:g}-{hi:g} Hz (roll, pitch, yaw, total) [deg/s]:")
    for key in ("before", "after"):
        v = n[key]
        say(f"  {key:<6} {v['roll_dps']:8.4f} {v['pitch_dps']:8.4f} {v['yaw_dps']:8.4f}  "
            f"{v['total_dps']:8.4f}")
    ch = n["change_db"]
    say(f"  change {'n/a' if ch is None else f'{ch:+.1f} dB'} (target {n['target_db']:+g} dB: "
        f"{'met' if n['met'] else 'NOT met'}); predicted from the raw spectrum "
        f"{r['predicted']['change_db']:+.1f} dB")
    if r["phase_lag"]:
        p = r["phase_lag"]
        say(f"  filter phase lag at {p['crossover_hz']:g} Hz: {p['before_deg']:.1f} -> "
            f"{p['after_deg']:.1f} deg")
    say(f"parameters: {r['parm_file']}; logs: {r['source_log']}, {r['after_log']}")
    # The sweep's margins are measured on the flying FC, so they carry the filters' lag.
    say(f"stability margins with these filters: silbridge tune sysid --params {r['parm_file']}")
