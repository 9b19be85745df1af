"""`silbridge bench --suite nav`: N1..N4 through the shared suite runner
(tools/benchmark/suite_command.py): options checked before any run, the campaign, the table
(printed, --json, OUT/nav.md, OUT/nav.json) and the report page (OUT/nav-report.md)."""

from __future__ import annotations

from silbridge.tools.benchmark.nav.campaign import result_dicts, run_nav_campaign
from silbridge.tools.benchmark.nav.plans import PLANS, plan_names
from silbridge.tools.benchmark.nav.report import write_nav_report
from silbridge.tools.benchmark.nav.table import markdown, summarize
from silbridge.tools.benchmark.suite_command import Suite, run_suite

SPEED = 5.0          # times real time when --speed is not given (ours and the autopilots)

NAV = Suite(name="nav", plans=tuple(PLANS), plan_names=plan_names, default_speed=SPEED,
            campaign=run_nav_campaign, result_dicts=result_dicts, summarize=summarize,
            markdown=markdown, write_report=write_nav_report)


def run_nav(args, paper_defaults: dict, fcs: list[str], arducopter, px4, speed_given: bool
            ) -> int:
    return run_suite(NAV, args, paper_defaults, fcs, arducopter, px4, speed_given)
