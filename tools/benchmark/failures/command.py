"""`silbridge bench --suite failures`: F1..F12 through the shared suite runner
(tools/benchmark/suite_command.py): options checked before any run, the campaign, the table
(printed, --json, OUT/failures.md, OUT/failures.json) and the results page
(OUT/failures-report.md)."""

from __future__ import annotations

from silbridge.tools.benchmark.failures.campaign import result_dicts, run_failure_campaign
from silbridge.tools.benchmark.failures.plans import PLANS, plan_names
from silbridge.tools.benchmark.failures.report import write_failures_report
from silbridge.tools.benchmark.failures.table import markdown, summarize
from silbridge.tools.benchmark.suite_command import Suite, run_suite

SPEED = 10.0    # times real time when --speed is not given: the client only watches here

FAILURES = Suite(name="failures", plans=tuple(PLANS), plan_names=plan_names,
                 default_speed=SPEED, campaign=run_failure_campaign, result_dicts=result_dicts,
                 summarize=summarize, markdown=markdown, write_report=write_failures_report)


def run_failures(args, paper_defaults: dict, fcs: list[str], arducopter, px4,
                 speed_given: bool) -> int:
    return run_suite(FAILURES, args, paper_defaults, fcs, arducopter, px4, speed_given)
