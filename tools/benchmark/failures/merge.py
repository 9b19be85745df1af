"""One table from several runs of the suite (`python -m silbridge.tools.benchmark.failures.merge
OUT DIR...`): the results of each DIR/failures.json, in the order given, summarised,
printed and written to OUT (failures.md, failures.json, failures-report.md) by the same
code as `bench --suite failures`. For a campaign split into parts (one autopilot or a few
plans at a time on a shared machine); the page names the commands of the parts. A run
(plan, autopilot, seed) in a later part replaces the same run of an earlier one (a part
flown again); a run whose fault the translation table no longer lets reach its autopilot
is listed as not measured, with the table's reason."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from silbridge.tools.benchmark.failures.campaign import FailureResult, result_dicts
from silbridge.tools.benchmark.failures.plans import PLANS
from silbridge.tools.benchmark.failures.report import write_failures_report
from silbridge.tools.benchmark.failures.table import markdown, summarize
from silbridge.tools.benchmark.failures.translate import unreachable
from silbridge.tools.benchmark.table1_compare import FC_LABELS


def _result(d: dict) -> FailureResult:
    m = {k: (math.nan if v is None else v) for k, v in (d.get("metrics") or {}).items()}
    return FailureResult(**{**d, "metrics": m, "sim_s": d.get("sim_s") or 0.0,
                            "wall_s": d.get("wall_s") or 0.0})


def merge(out: str, parts: list[str]) -> str:
    by_run, runs, commands = {}, 0, []
    for part in parts:
        table = json.loads((Path(part) / "failures.json").read_text())
        for d in table["results"]:      # a later part's run of the same seed replaces it
            r = _result(d)
            why = unreachable(r.fc, PLANS[r.plan])    # the translation table as it is now
            if why and r.status != "not_measured":
                r = FailureResult(r.plan, r.fc, r.seed, "not_measured", "; ".join(why))
            by_run[(r.plan, r.fc, r.seed)] = r
        runs = max(runs, table["runs"])
        commands.append(table.get("command", part))
    results = sorted(by_run.values(), key=lambda r: (int(r.plan[1:]), list(FC_LABELS).index(r.fc),
                                                     r.seed))
    fcs = [fc for fc in FC_LABELS if any(r.fc == fc for r in results)]
    summary = summarize(results, fcs)
    md = markdown(summary, fcs, runs)
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "failures.md").write_text(md + "\n")
    (out_dir / "failures.json").write_text(json.dumps(
        {"suite": "failures", "fc": fcs, "runs": runs, "parts": commands, "summary": summary,
         "results": result_dicts(results)}, indent=2) + "\n")
    write_failures_report(results, md, out_dir, commands)
    return md


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: python -m silbridge.tools.benchmark.failures.merge OUT DIR [DIR ...]")
    print(merge(sys.argv[1], sys.argv[2:]))
