"""`silbridge ablate`: the campaign with each stabilisation feature off alone and all off.

Each variant is compared with `full`, the paper's controller with every ablated feature on
(tools/benchmark/ablation.py), not with the declared defaults (a `defaults` row shows those),
paired by seed with the one rule of Table 1 (tools/benchmark/ablation_table.py: median
difference, 95 % bootstrap interval, verdict). With a harmonic notch among the parameters
the notch's own variants join (off, a plain low-pass instead, the in-flight FFT). Writes
ablation.md, ablation.json (the per-run figures too) and, unless --no-report,
report/index.html: the full controller's Table 1 and plots with the verdicts beside them."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from silbridge.tools.benchmark import ablation_table
from silbridge.tools.benchmark.ablation import variants
from silbridge.tools.benchmark.campaign import make_specs, run_campaign
from silbridge.tools.benchmark.report import write_report
from silbridge.tools.benchmark.table1 import aggregate, markdown, scenario_key
from silbridge.tools.cli.cmd_bench import add_campaign_arguments, campaign_inputs, windows_dict

HELP = ("ablation: the campaign with each stabilisation feature off, paired by seed against "
        "the full FC")

# Every variant flies the whole campaign: fewer runs than bench's 20 keep it affordable.
DEFAULT_RUNS = 5
DEFAULT_OUT = "ablate-out"


def add_arguments(p) -> None:
    add_campaign_arguments(p)
    # set_defaults also changes what --help shows: the help texts use %(default)s.
    p.set_defaults(runs=DEFAULT_RUNS, out=DEFAULT_OUT)


def run(args) -> int:
    scenarios, windows, params = campaign_inputs(args)
    out_dir = Path(args.out)
    all_specs = []
    for label, variant_params in variants(params):
        all_specs += make_specs(scenarios, args.runs, args.duration, out_dir,
                                base_seed=args.seed, imu_hz=args.imu_hz,
                                params=tuple(sorted(variant_params.items())), variant=label,
                                windows=windows,
                                keep_logs=args.keep_logs, viz_hz=args.viz_hz)
    t0 = time.monotonic()
    results = run_campaign(all_specs, jobs=args.jobs, executor=args.executor,
                           ray_address=args.ray_address, label="ablate")
    from silbridge.tools.loop.stop_signals import STOP
    partial = [r.spec.log_path for r in results
               if r.summary.get("interrupted") and not r.summary.get("skipped")]
    results = [r for r in results if not r.summary.get("interrupted")]
    if STOP.requested:
        stopped = {"interrupted": STOP.name, "runs_planned": len(all_specs),
                   "runs_done": len(results), "partial_logs": partial}
        print(f"ablate: INTERRUPTED by {STOP.name}: {len(results)} of {len(all_specs)} runs "
              f"finished", file=sys.stderr)
        if not any(r.spec.variant == "full" for r in results):
            print(json.dumps(stopped) if args.json else
                  "ablate: no full-variant run finished: no table")
            return STOP.exit_code()
    by_variant: dict[str, list] = {}
    for r in results:
        by_variant.setdefault(r.spec.variant, []).append(r)
    tables = {v: aggregate(rs) for v, rs in by_variant.items()}
    full = tables["full"]
    rows = ablation_table.run_rows(results, lambda r: scenario_key(r.spec.scenario))
    judged = ablation_table.payload(rows)
    md = ablation_table.markdown(rows, judged["paired"])
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "ablation.md").write_text(md)
    payload = {"variants": tables, **judged, "wall_s": time.monotonic() - t0,
               "runs_per_variant": args.runs, "duration_s": args.duration,
               "params": dict(params), "windows": windows_dict(windows),
               **(stopped if STOP.requested else {})}
    (out_dir / "ablation.json").write_text(json.dumps(payload, indent=2) + "\n")
    if not args.no_report:
        # The full controller's Table 1 and plots, with the verdicts as a section of the page.
        page = {**full, "runs": args.runs, "duration_s": args.duration,
                "params": dict(params)}
        payload["report"] = str(write_report(by_variant["full"], markdown(page), page, out_dir,
                                             extra_sections=[("Ablation", md)]))
    print(json.dumps(payload) if args.json else md)
    if "report" in payload and not args.json:
        print(f"report {payload['report']}")
    return STOP.exit_code(0)
