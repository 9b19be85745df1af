"""One `silbridge speed --campaign` run: the bench's campaign (tools/benchmark/campaign.py) of
N runs of each of S1..S4 on --jobs workers, in this fresh interpreter, timed as `silbridge
bench` times it (run_campaign alone: worker start-up included, the report not). Prints one JSON
object: the overall factor (all simulated seconds over that wall time) and the runs' own.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

SCENARIOS = ["S1", "S2", "S3", "S4"]


def main() -> None:
    from silbridge.tools.benchmark.campaign import make_specs, run_campaign

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--jobs", type=int, required=True)
    ap.add_argument("--runs", type=int, required=True, help="runs of each scenario")
    ap.add_argument("--duration", type=float, required=True, help="simulated seconds per run")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="silbridge-speed-campaign-") as tmp:
        specs = make_specs(SCENARIOS, a.runs, a.duration, Path(tmp), keep_logs="none")
        t0 = time.monotonic()
        res = run_campaign(specs, jobs=a.jobs, progress=False)
        wall_s = time.monotonic() - t0
    sim_s = sum(r.summary["sim_s"] for r in res)
    # Where the workers' time goes besides flying: each run's set-up and its log read back,
    # checked and scored (its wall time less its flight's), the workers' start and the end
    # of the campaign when fewer runs than workers are left.
    flight_s = [r.summary["sim_s"] / r.summary["realtime_factor"] for r in res]
    print(json.dumps({"jobs": a.jobs, "runs": len(res), "sim_s": sim_s, "wall_s": wall_s,
                      "realtime_factor": sim_s / wall_s,
                      "run_realtime_factor": statistics.median(
                          r.summary["realtime_factor"] for r in res),
                      "flying": sum(flight_s) / (min(a.jobs, len(res)) * wall_s),
                      "outside_flight_s": statistics.median(
                          r.wall_s - f for r, f in zip(res, flight_s))}))


if __name__ == "__main__":      # spawn workers import this file again: only the parent runs
    main()
