"""What `bench --suite nav` and `--suite failures` share: bench's options read and checked
before any run, then the campaign, the table (printed, --json, OUT/<suite>.md and .json) and
the report page. Each suite hands in its plans, campaign, table and report (a `Suite`).

The paper suite's options that mean nothing to a flown suite (its windows, --duration,
--imu-hz, --viz-hz, Ray) are refused when given, rather than silently ignored.
"""

from __future__ import annotations

import json
import shlex
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from silbridge.tools.benchmark.campaign import CampaignError

PAPER_SCENARIOS = "S1,S2,S3,S4"    # bench's --scenarios default: for a flown suite, all its plans


@dataclass(frozen=True)
class Suite:
    name: str                 # "nav", "failures": also the stem of OUT/<name>.md/.json
    plans: tuple              # every plan, flown when --scenarios is left at its default
    plan_names: Callable      # --scenarios text -> plan names (refuses unknown ones)
    default_speed: float      # times real time when --speed is not given
    campaign: Callable        # (fcs, plans, runs, seed, out_dir, speed=, arducopter=, px4=,
                              #  params=, keep_logs=) -> results
    result_dicts: Callable
    summarize: Callable
    markdown: Callable
    write_report: Callable    # (results, md, out_dir, command) -> page path


def refuse_paper_options(args, paper_defaults: dict) -> None:
    given = [flag for flag, (value, default) in paper_defaults.items() if value != default]
    if args.executor != "local" or args.jobs is not None:
        given.append(f"--executor/--jobs ({args.suite} runs one at a time: each flies in real time)")
    if given:
        raise CampaignError(f"{', '.join(given)}: options of the paper suite; --suite "
                            f"{args.suite} flies its own plans: leave them out")


def run_suite(suite: Suite, args, paper_defaults: dict, fcs: list[str], arducopter, px4,
              speed_given: bool) -> int:
    """args: bench's parsed options; paper_defaults: {flag: (value, default)} of the
    paper-only options; arducopter/px4: the binaries bench checked for the --fc asked."""
    from silbridge.tools.benchmark.run_params import run_params
    from silbridge.tools.loop.stop_signals import STOP

    refuse_paper_options(args, paper_defaults)
    plans = list(suite.plans) if args.scenarios == PAPER_SCENARIOS else suite.plan_names(args.scenarios)
    if args.runs < 1:
        raise CampaignError("--runs must be >= 1")
    speed = args.speed if speed_given else suite.default_speed
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
    results = suite.campaign(fcs, plans, args.runs, args.seed, str(out_dir), speed=speed,
                             arducopter=arducopter, px4=px4, params=params,
                             keep_logs=args.keep_logs)
    summary = suite.summarize(results, fcs)
    command = "silbridge bench " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    table = {"suite": suite.name, "command": command, "fc": fcs, "plans": plans,
             "runs": args.runs, "seed": args.seed, "speed": speed,
             "wall_s": time.monotonic() - t0, "params": dict(params), "summary": summary,
             "results": suite.result_dicts(results)}
    if STOP.requested:
        table["interrupted"] = STOP.name
    md = suite.markdown(summary, fcs, args.runs)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / f"{suite.name}.md").write_text(md + "\n")
    (out_dir / f"{suite.name}.json").write_text(json.dumps(table, indent=2) + "\n")
    page = None if args.no_report else suite.write_report(results, md, out_dir, command)
    if args.json:
        print(json.dumps(table))
    else:
        print(md)
        print(f"\n{len(results)} runs in {table['wall_s']:.0f} s wall; logs and tables in "
              f"{out_dir}/" + (f", report {page}" if page else ""))
    return STOP.exit_code(0)
