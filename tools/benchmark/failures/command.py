"""`silbridge bench --suite failures`: the options of `bench` as this suite reads them,
checked before any run, then the campaign, the table (printed, --json, OUT/failures.md,
OUT/failures.json) and the results page (OUT/failures-report.md)."""

from __future__ import annotations

import json
import shlex
import sys
import time
from pathlib import Path

from silbridge.tools.benchmark.campaign import CampaignError
from silbridge.tools.benchmark.failures.campaign import result_dicts, run_failure_campaign
from silbridge.tools.benchmark.failures.plans import PLANS, plan_names
from silbridge.tools.benchmark.failures.report import write_failures_report
from silbridge.tools.benchmark.failures.table import markdown, summarize
from silbridge.tools.benchmark.nav.command import PAPER_SCENARIOS, _refuse_paper_options

SPEED = 10.0    # times real time when --speed is not given: the client only watches here


def run_failures(args, paper_defaults: dict, fcs: list[str], arducopter, px4,
                 speed_given: bool) -> int:
    from silbridge.tools.benchmark.run_params import run_params
    from silbridge.tools.loop.stop_signals import STOP

    _refuse_paper_options(args, paper_defaults)
    plans = list(PLANS) if args.scenarios == PAPER_SCENARIOS else plan_names(args.scenarios)
    if args.runs < 1:
        raise CampaignError("--runs must be >= 1")
    speed = args.speed if speed_given else SPEED
    if speed <= 0:
        raise CampaignError("--speed must be > 0")
    params = tuple(sorted(run_params(args.param_file, args.param,
                                     say=lambda s: print(f"bench: {s}", file=sys.stderr))
                          .items()))
    if params and "ours" not in fcs:
        raise CampaignError("--param/--params: for our FC's runs: add ours to --fc, or leave "
                            "them out")
    out_dir = Path(args.out)
    t0 = time.monotonic()
    results = run_failure_campaign(fcs, plans, args.runs, args.seed, str(out_dir), speed=speed,
                                   arducopter=arducopter, px4=px4, params=params,
                                   keep_logs=args.keep_logs)
    summary = summarize(results, fcs)
    command = "silbridge bench " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    table = {"suite": "failures", "command": command, "fc": fcs, "plans": plans,
             "runs": args.runs, "seed": args.seed, "speed": speed, "wall_s": time.monotonic() - t0,
             "params": dict(params), "summary": summary, "results": result_dicts(results)}
    if STOP.requested:
        table["interrupted"] = STOP.name
    md = markdown(summary, fcs, args.runs)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "failures.md").write_text(md + "\n")
    (out_dir / "failures.json").write_text(json.dumps(table, indent=2) + "\n")
    page = None
    if not args.no_report:
        page = write_failures_report(results, md, out_dir, command)
    if args.json:
        print(json.dumps(table))
    else:
        print(md)
        print(f"\n{len(results)} runs in {table['wall_s']:.0f} s wall; logs and tables in "
              f"{out_dir}/" + (f", report {page}" if page else ""))
    return STOP.exit_code(0)
