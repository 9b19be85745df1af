"""`silbridge tune anchor`: ArduCopter's AUTOTUNE gains beside ours.

Flies the real ArduCopter's AUTOTUNE on our physics (tools/tune/tune_anchor.py),
puts its gains into our FC, and flies the same Table 1 (S1, S4) and the same
sweeps as `tune auto` does for our gains (tune_compare.py): defaults, AUTOTUNE's
as saved, AUTOTUNE's cut to ArduCopter's documented ranges, and (with --ours
FILE) our own tuned set, side by side. Both AUTOTUNE .parm files go to `tune auto
--compare`, which reproduces the whole comparison in one command.
"""

from __future__ import annotations

from pathlib import Path

from silbridge.tools.tune.tune_auto import AutoConfig, check
from silbridge.tools.tune.tune_compare import comparison_table, score_set, summary
from silbridge.tools.tune.tune_sysid import SweepConfig, TuneError


def run_anchor(args, axes, base: dict, out_dir: Path, pool, say) -> dict:
    from silbridge.mavlink.gcs.params_file import load_parm

    from silbridge.tools.autopilots.ardupilot.sitl import require_arducopter
    from silbridge.tools.benchmark.table1 import markdown
    from silbridge.tools.tune.tune_anchor import (AXIS_BITS, for_our_fc, run_autotune,
                                                  within_documented)
    from silbridge.tools.tune.tune_parm import write_parm
    from silbridge.tools.tune.tune_report import write_index

    binary = require_arducopter(args.arducopter)
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
    documented = within_documented(applied)
    parm_doc = write_parm(out_dir / "arducopter_autotune_documented.parm", documented,
                          header=f"ArduCopter AUTOTUNE on silbridge physics ({binary}), "
                                 f"cut to ArduCopter's documented ranges")
    cfg = AutoConfig(axes=axes, runs=args.runs, seed=args.seed,
                     check_sweep=SweepConfig(seed=args.seed))
    work = out_dir / "runs"
    work.mkdir(exist_ok=True)
    sets = {"defaults": dict(base), "arducopter": {**base, **applied},
            "arducopter_documented": {**base, **documented}}
    if args.ours:
        sets["ours"] = {**base, **{n.upper(): v for n, v in load_parm(args.ours)}}
    cols = {label: score_set(pool, params, cfg, work, label) for label, params in sets.items()}
    if cols["defaults"]["failed"]:
        raise TuneError(f"the defaults fail: {cols['defaults']['failed']}")
    figures = {label: col["means"] for label, col in cols.items()}
    margins = {label: col["margins"] for label, col in cols.items()}
    verdicts = {label: (check(figures["defaults"], figures[label], margins[label], cfg)
                        if figures[label] else {"met": False, "note": cols[label]["failed"]})
                for label in sets if label != "defaults"}
    comparison = comparison_table(cols, axes, sets)
    tables = [("Comparison", comparison)] + [
        (f"Table 1: {label}", markdown(col["table"], paper=False, title=label))
        for label, col in cols.items() if col["table"] is not None]
    result = {"arducopter": {"gains": at["gains"], "clipped": clipped,
                             "tune_sim_s": at["tune_sim_s"], "wall_s": at["wall_s"],
                             "statustext": at["statustext"][-6:]},
              "params": applied, "parm_file": str(parm),
              "parm_file_documented": str(parm_doc),
              "sets": {label: summary(col) for label, col in cols.items()},
              "table1": figures, "margins": margins, "verdicts": verdicts}
    write_index(out_dir, "silbridge tune anchor: ArduCopter AUTOTUNE beside ours", result,
                tables, [])
    say(comparison)
    if clipped:
        say("clipped to our declared ranges: " + ", ".join(
            f"{k} {v[0]:g} -> {v[1]:g}" for k, v in clipped.items()))
    say(f"parameters: {parm}, {parm_doc}; report: {out_dir / 'index.html'}")
    return result
