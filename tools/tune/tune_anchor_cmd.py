"""`silbridge tune anchor`: ArduCopter's AUTOTUNE gains beside ours.

Flies the real ArduCopter's AUTOTUNE on our physics (tools/tune/tune_anchor.py),
puts its gains into our FC, and flies the same Table 1 (S1, S4) and the same
sweeps as `tune auto` does for our gains: defaults, AUTOTUNE's, and (with
--ours FILE) our own tuned set, side by side.
"""

from __future__ import annotations

from pathlib import Path

from silbridge.tools.tune.tune_auto import AutoConfig, check, means, table1_runs
from silbridge.tools.tune.tune_sysid import SweepConfig, TuneError, identify


def run_anchor(args, axes, base: dict, out_dir: Path, pool, say) -> dict:
    from silbridge.mavlink.gcs.params_file import load_parm

    from silbridge.tools.autopilots.sitl_ardupilot import HOW_TO_GET, find_arducopter
    from silbridge.tools.benchmark.table1 import aggregate, markdown
    from silbridge.tools.tune.tune_anchor import AXIS_BITS, for_our_fc, run_autotune
    from silbridge.tools.tune.tune_parm import write_parm
    from silbridge.tools.tune.tune_report import margins_table, write_index

    binary = find_arducopter(args.sitl)
    if binary is None:
        raise TuneError(HOW_TO_GET)
    if args.runs < 1:
        raise TuneError("--runs must be >= 1")
    out_dir.mkdir(parents=True, exist_ok=True)
    mask = sum(AXIS_BITS[a] for a in axes)
    say(f"ArduCopter AUTOTUNE (AUTOTUNE_AXES {mask}, AGGR {args.aggr:g}) on our physics ...")
    at = run_autotune(binary, axes_mask=mask, aggr=args.aggr, seed=args.seed)
    say(f"AUTOTUNE done: {at['tune_sim_s']:.0f} s of tuning flight, {at['wall_s']:.0f} s wall")
    applied, clipped = for_our_fc(at["gains"], axes)
    parm = write_parm(out_dir / "arducopter_autotune.parm", applied,
                      header=f"ArduCopter AUTOTUNE on silbridge physics ({binary})")
    cfg = AutoConfig(axes=axes, runs=args.runs, seed=args.seed)
    work = out_dir / "runs"
    work.mkdir(exist_ok=True)
    sets = {"defaults": dict(base), "arducopter": {**base, **applied}}
    if args.ours:
        sets["ours"] = {**base, **{n.upper(): v for n, v in load_parm(args.ours)}}
    tables, margins, figures = [], {}, {}
    for label, params in sets.items():
        runs = table1_runs(pool, params, cfg, work, label)
        tab = aggregate(runs)
        figures[label] = means(tab)
        margins[label] = {a: r.summary for a, r in
                          identify(axes, SweepConfig(seed=args.seed), params,
                                   runner=pool.map).items()}
        tables.append((f"Table 1: {label}", markdown(tab, paper=False, title=label)))
        tables.append((f"Margins: {label}", margins_table(margins[label])))
    verdicts = {label: check(figures["defaults"], figures[label], margins[label], cfg)
                for label in sets if label != "defaults"}
    result = {"arducopter": {"gains": at["gains"], "clipped": clipped,
                             "tune_sim_s": at["tune_sim_s"], "wall_s": at["wall_s"],
                             "statustext": at["statustext"][-6:]},
              "params": applied, "parm_file": str(parm), "table1": figures,
              "margins": margins, "verdicts": verdicts}
    write_index(out_dir, "silbridge tune anchor: ArduCopter AUTOTUNE beside ours", result,
                tables, [])
    for label in sets:
        f = figures[label]
        tk = check(f, f, margins[label], cfg)["track_metric"]
        m = "; ".join(f"{a} PM {margins[label][a].get('phase_margin_deg') or float('nan'):.1f} deg"
                      for a in axes)
        say(f"{label:>10}: S4 {tk} {f['S4'][tk]:.3f} deg, S1 p-p {f['S1']['pwm_pp_us']:.1f} us; {m}")
    if clipped:
        say("clipped to our declared ranges: " + ", ".join(
            f"{k} {v[0]:g} -> {v[1]:g}" for k, v in clipped.items()))
    say(f"parameters: {parm}; report: {out_dir / 'index.html'}")
    return result
