"""The three `silbridge tune` actions: fly, analyse, write the report, and
return the --json object (tools/cli/cmd_tune.py parses the options)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from silbridge.tools.tune.tune_freq import Frf
from silbridge.tools.tune.tune_sysid import COHERENCE_MIN, SweepConfig, identify, with_overrides


def _fmt(v, fmt="{:.1f}"):
    return "n/a" if v is None else fmt.format(v)


def run_sysid(args, axes, base: dict, out_dir: Path, pool, say) -> dict:
    from silbridge.tools.tune.tune_model import plant_agreement, plant_frf
    from silbridge.tools.tune.tune_report import TITLES, bode_png, margins_table, write_index

    cfg = with_overrides(SweepConfig(seed=args.seed), f_start_hz=args.f_start,
                         f_stop_hz=args.f_stop, t_rec_s=args.t_rec, t_fade_in_s=args.fade_in,
                         magnitude_rate_dps=args.magnitude_rate,
                         magnitude_mixer=args.magnitude_mixer)
    inj = ("output", "input") if args.inject == "both" else (args.inject,)
    results = identify(axes, cfg, base, injections=inj, runner=pool.map)
    out_dir.mkdir(parents=True, exist_ok=True)
    images = []
    summaries = {}
    band = (cfg.f_start_hz, cfg.f_stop_hz)
    pwm_hz = float(base.get("SB_PWM_HZ", 400.0))
    for axis, res in results.items():
        s = dict(res.summary)
        if "plant" in res.frfs:
            pl = res.frfs["plant"]
            s["plant_vs_model"] = plant_agreement(pl.f_hz, pl.h, pl.coherence, axis, band_hz=band,
                                                  coh_min=COHERENCE_MIN, pwm_hz=pwm_hz)
        summaries[axis] = s
        for name, frf in res.frfs.items():
            title, _unit = TITLES.get(name, (name, ""))
            model = None
            if name == "plant":
                f = np.geomspace(*band, 200)
                model = Frf(f, plant_frf(f, axis, pwm_hz=pwm_hz), np.ones_like(f))
            marg = s if name == "open_loop" else (s.get("rate_loop") if name == "rate_loop"
                                                  else None)
            images.append(bode_png(out_dir, f"{axis}_{name}.png", frf, title=f"{axis}: {title}",
                                   f_band=band, coh_min=COHERENCE_MIN, model=model,
                                   margins=marg))
    sweep = {k: v for k, v in cfg.__dict__.items()}
    summary = {"axes": summaries, "sweep": sweep, "coherence_min": COHERENCE_MIN,
               "params": base, "report": str(out_dir / "index.html")}
    write_index(out_dir, "silbridge tune sysid", summary,
                [("Margins and bandwidth", margins_table(summaries))], images)
    for axis, s in summaries.items():
        gm = (f"GM {_fmt(s['gain_margin_db'])} dB at {_fmt(s['phase_crossover_hz'], '{:.2f}')} Hz"
              if s.get("gain_margin_db") is not None or s.get("gain_margin_min_db") is None
              else f"GM >= {s['gain_margin_min_db']:.1f} dB (phase crossover above the band)")
        say(f"{axis}: PM {_fmt(s['phase_margin_deg'])} deg at {_fmt(s['crossover_hz'], '{:.2f}')} Hz, "
            f"{gm}, "
            f"delay margin {_fmt(s['delay_margin_ms'])} ms, bandwidth "
            f"{_fmt(s['bandwidth_hz'], '{:.2f}')} Hz")
        pv = s.get("plant_vs_model")
        if pv and pv["band_hz"]:
            say(f"  plant vs linearised model over {pv['band_hz'][0]:.2f}-{pv['band_hz'][1]:.1f} Hz "
                f"(coherence >= {COHERENCE_MIN}): {pv['max_gain_err_db']:.2f} dB, "
                f"{pv['max_phase_err_deg']:.1f} deg at most")
    say(f"report: {out_dir / 'index.html'}")
    return summary


def run_step(args, axes, base: dict, out_dir: Path, pool, say) -> dict:
    from silbridge.tools.tune.tune_report import step_png, write_index
    from silbridge.tools.tune.tune_step import StepConfig, step_task

    if args.amplitude <= 0 or args.hold <= 0 or args.repeat < 1:
        from silbridge.tools.tune.tune_sysid import TuneError
        raise TuneError("--amplitude and --hold must be > 0 and --repeat >= 1")
    cfg = StepConfig(amplitude_deg=args.amplitude, hold_s=args.hold, repeat=args.repeat,
                     period_s=max(8.0, 5 * args.hold), seed=args.seed)
    out_dir.mkdir(parents=True, exist_ok=True)
    results = pool.map(step_task, [(a, cfg, base, str(out_dir)) for a in axes])
    images, axes_out, rows = [], {}, []
    for axis, res, note in results:
        t, cmd, actual, idx = res.pop("series")
        # one doublet, from 0.5 s before its first edge to 2 s after its last
        last = idx[min(len(idx) - 1, 3 if axis != "yaw" else 1)]
        i0 = int(np.searchsorted(t, t[idx[0]] - 0.5))
        i1 = int(np.searchsorted(t, t[last] + 2.0))
        images.append(step_png(out_dir, f"{axis}_doublet.png", t[i0:i1] - t[idx[0]],
                               np.degrees(cmd[i0:i1]), np.degrees(actual[i0:i1]),
                               title=f"{axis}: doublet, command vs true", ylabel="deg"))
        axes_out[axis] = {"step": res["step"], "doublet": res["doublet"], "steps": res["steps"],
                          **({"note": note} if note else {})}
        st = res["step"]
        rows.append(f"| {axis} | {_fmt(st['rise_time_s'], '{:.3f}')} | "
                    f"{_fmt(st['overshoot_pct'])} | {_fmt(st['settling_time_s'], '{:.3f}')} | "
                    f"{_fmt(res['doublet']['rms_err_deg'], '{:.2f}')} |")
        say(f"{axis}: rise {_fmt(st['rise_time_s'], '{:.3f}')} s, overshoot "
            f"{_fmt(st['overshoot_pct'])} %, settling {_fmt(st['settling_time_s'], '{:.3f}')} s, "
            f"doublet RMS error {_fmt(res['doublet']['rms_err_deg'], '{:.2f}')} deg"
            + (f"  ({note})" if note else ""))
    table = ("| axis | rise (s) | overshoot (%) | settling 5 % (s) | doublet RMS (deg) |\n"
             "|---|---|---|---|---|\n" + "\n".join(rows))
    summary = {"axes": axes_out, "amplitude_deg": cfg.amplitude_deg, "params": base,
               "report": str(out_dir / "index.html")}
    write_index(out_dir, "silbridge tune step", summary, [("Step responses", table)], images)
    say(f"report: {out_dir / 'index.html'}")
    return summary


def run_auto_cmd(args, axes, base: dict, out_dir: Path, pool, say) -> dict:
    from silbridge.tools.tune.tune_auto import AutoConfig, run_auto
    from silbridge.tools.tune.tune_compare import load_compare
    from silbridge.tools.tune.tune_sysid import TuneError

    if args.trials < 1 or args.runs < 1 or args.batch < 1:
        raise TuneError("--trials, --runs and --batch must be >= 1")
    compare = []
    for path in args.compare:
        label, values = load_compare(path)
        if label in ("defaults", "tuned") or label in dict(compare):
            raise TuneError(f"--compare {path}: name the file apart from defaults, tuned "
                            f"and the other --compare files")
        compare.append((label, tuple(sorted(values.items()))))
    cfg = AutoConfig(axes=axes, trials=args.trials, runs=args.runs, seed=args.seed,
                     batch=args.batch, base_params=tuple(sorted(base.items())),
                     pm_min=args.pm_min, gm_min=args.gm_min,
                     input_tc=not args.keep_input_tc, compare=tuple(compare))
    res = run_auto(cfg, out_dir, pool=pool, progress=not args.no_progress, out=say)
    d = res["details"]
    r = res["result"]
    say(d["comparison_md"])
    v = d["verdict"]
    if "beats" in v:
        say("S4 vs the command, tuned better than: " + ", ".join(
            f"{lab} {'(crashed)' if ok == 'crashed' else ok}" for lab, ok in v["beats"].items()))
    say(f"targets met: {v.get('met')}; {d['feasible_trials']}/{d['trials']} trials "
        f"feasible; search {d['search_wall_s']:.0f} s, total {d['wall_s']:.0f} s")
    say(f"parameters: {r['parm_file']}; report: {out_dir / 'index.html'}")
    return r
