"""`silbridge bench --suite nav`: the options of `bench` as the nav suite reads them, checked
before any run, then the campaign, the table (printed, --json, OUT/nav.md, OUT/nav.json) and
the report page (OUT/nav-report.md).

The paper suite's options that mean nothing here (its windows, --duration, --imu-hz,
--viz-hz, Ray) are refused when given, rather than silently ignored.
"""

from __future__ import annotations

import json
import shlex
import sys
import time
from pathlib import Path

from silbridge.tools.benchmark.campaign import CampaignError
from silbridge.tools.benchmark.nav.campaign import result_dicts, run_nav_campaign
from silbridge.tools.benchmark.nav.plans import PLANS, plan_names
from silbridge.tools.benchmark.nav.report import write_nav_report
from silbridge.tools.benchmark.nav.table import markdown, summarize

SPEED = 5.0          # times real time when --speed is not given (ours and the autopilots)
PAPER_SCENARIOS = "S1,S2,S3,S4"    # bench's --scenarios default: for nav it means N1..N4


def _refuse_paper_options(args, paper_defaults: dict) -> None:
    given = [flag for flag, (value, default) in paper_defaults.items() if value != default]
    if args.executor != "local" or args.jobs is not None:
        given.append("--executor/--jobs (nav runs one at a time: each flies in real time)")
    if given:
        raise CampaignError(f"{', '.join(given)}: options of the paper suite; --suite "
                            f"{args.suite} flies its own plans: leave them out")


def run_nav(args, paper_defaults: dict, fcs: list[str], arducopter, px4, speed_given: bool
            ) -> int:
    """args: bench's parsed options; paper_defaults: {flag: (value, default)} of the
    paper-only options; arducopter/px4: the binaries bench checked for the --fc asked."""
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
    results = run_nav_campaign(fcs, plans, args.runs, args.seed, str(out_dir), speed=speed,
                               arducopter=arducopter, px4=px4, params=params,
                               keep_logs=args.keep_logs)
    summary = summarize(results, fcs)
    table = {"suite": "nav", "fc": fcs, "plans": plans, "runs": args.runs, "seed": args.seed,
             "speed": speed, "wall_s": time.monotonic() - t0, "params": dict(params),
             "summary": summary, "results": result_dicts(results)}
    if STOP.requested:
        table["interrupted"] = STOP.name
    md = markdown(summary, fcs, args.runs)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "nav.md").write_text(md + "\n")
    (out_dir / "nav.json").write_text(json.dumps(table, indent=2) + "\n")
    page = None
    if not args.no_report:
        command = "silbridge bench " + " ".join(shlex.quote(a) for a in sys.argv[2:])
        page = write_nav_report(results, md, out_dir, command)
    if args.json:
        print(json.dumps(table))
    else:
        print(md)
        print(f"\n{len(results)} runs in {table['wall_s']:.0f} s wall; logs and tables in "
              f"{out_dir}/" + (f", report {page}" if page else ""))
    return STOP.exit_code(0)
