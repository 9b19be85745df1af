"""The paper's future work (iii), measured: our FC under added sensor latency and record loss.

    python -m silbridge.tools.benchmark.link_table [--scenario S1] [--runs 3] [--duration 30]

Each cell of the grid (sensor latency 0, 2, 5, 10, 20 ms x sensor records dropped 0, 10,
30 %) flies the scenario with a [[failure]] of unit "link", instance 1 (bridge to FC), from
--fault-from seconds to the end, on seeds 1..N (the same seeds in every cell), in lockstep
with the FC in this process. Scored from --score-from to the end: the attitude error RMS
against the scenario's command (as the summary's, but sampled every physics step), its
largest value, and whether the flight stayed stable: no crash and the error never beyond
30 deg, ArduCopter's default lean-angle limit (ANGLE_MAX 3000 cdeg): past it the FC has
lost the attitude it was asked to hold. Writes sil-link-faults-<scenario>.json (every run and
the cells) and .md (the table) to --out.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tomllib
from pathlib import Path

import numpy as np

from silbridge.bridge.bridge_driver import prepare_segment, run_bridge
from silbridge.bridge.scenario import SCENARIO_DIR, scenario_from_dict
from silbridge.bridge.simulator import Simulator
from silbridge.shm import Segment
from silbridge.tools.loop.fc_param_events import check_fc_param
from silbridge.tools.loop.flight import bridge_config, FlightOptions, make_fc_loop

LATENCY_MS = (0, 2, 5, 10, 20)
DROP_PCT = (0, 10, 30)
STABLE_MAX_DEG = 30.0       # ArduCopter ANGLE_MAX default, 3000 cdeg
_NS = 1_000_000_000


class _ErrorWatch:
    """The bridge's sink: after every physics step, the attitude error against the
    scenario's command (from score_ns on)."""

    pwm_records = None

    def __init__(self, sim, score_ns: int):
        self.sim, self.score_ns = sim, score_ns
        self.sq, self.n, self.worst = 0.0, 0, 0.0

    def rotor(self, sim_ns: int) -> None:
        if sim_ns < self.score_ns:
            return
        roll, pitch, _ = self.sim.roll_pitch_alt()
        cmd = self.sim.command
        e2 = (roll - cmd["roll_rad"]) ** 2 + (pitch - cmd["pitch_rad"]) ** 2
        self.sq += e2
        self.n += 1
        self.worst = max(self.worst, e2)

    def event(self, sim_ns, kind, text, **fields) -> None:
        pass


def scenario_raw(name: str) -> dict:
    return tomllib.loads((SCENARIO_DIR / f"{name}.toml").read_text())


def fly_cell(raw: dict, seed: int, latency_ms: float, drop_pct: float, duration_s: float,
             fault_from_s: float, score_from_s: float) -> dict:
    """One flight of a cell: the scenario with the link faults, FC in this process."""
    raw = dict(raw, duration_s=duration_s, failure=[
        {"unit": "link", "type": "latency", "instance": 1, "delay_s": latency_ms / 1e3,
         "at_s": fault_from_s},
        {"unit": "link", "type": "drop", "instance": 1, "probability": drop_pct / 100.0,
         "at_s": fault_from_s}])
    sc = scenario_from_dict(raw, source=f"{raw['name']}+link", seed=seed,
                            check_fc_param=check_fc_param)
    sim = Simulator(sc)
    cfg = bridge_config(FlightOptions(duration_s=duration_s), sc)
    watch = _ErrorWatch(sim, int(score_from_s * _NS))
    name = f"linktab-{os.getpid()}"
    with Segment.create(name) as seg:
        prepare_segment(seg, sim, cfg)
        with Segment.attach(name) as fc_seg:
            fc = make_fc_loop(fc_seg)
            res = run_bridge(sim, seg, cfg, fc_poll=fc.poll, sink=watch, out=lambda s: None)
    rms = math.degrees(math.sqrt(watch.sq / watch.n)) if watch.n else None
    worst = math.degrees(math.sqrt(watch.worst))
    return {"seed": seed, "latency_ms": latency_ms, "drop_pct": drop_pct,
            "att_rms_deg": rms, "att_max_deg": worst, "crashed": res.crashed,
            "stable": not res.crashed and worst < STABLE_MAX_DEG, "link": res.link}


def summarise(rows: list[dict], latencies, drops) -> list[dict]:
    """Per cell: mean and standard deviation of the RMS, the worst error, stable runs."""
    cells = []
    for lat in latencies:
        for drop in drops:
            rs = [r for r in rows if r["latency_ms"] == lat and r["drop_pct"] == drop]
            if not rs:
                continue
            rms = np.array([r["att_rms_deg"] for r in rs], dtype=float)
            cells.append({"latency_ms": lat, "drop_pct": drop, "runs": len(rs),
                          "att_rms_mean_deg": float(rms.mean()),
                          "att_rms_std_deg": float(rms.std(ddof=1)) if len(rs) > 1 else 0.0,
                          "att_max_deg": max(r["att_max_deg"] for r in rs),
                          "stable_runs": sum(r["stable"] for r in rs)})
    return cells


def markdown(cells: list[dict], meta: dict) -> str:
    drops = meta["drop_pct"]
    lines = [f"Attitude error RMS (deg, mean +- sd over {meta['runs']} seeds) of our FC in "
             f"{meta['scenario']}, sensor link faulty from {meta['fault_from_s']:g} s, scored "
             f"{meta['score_from_s']:g}-{meta['duration_s']:g} s; in brackets the largest "
             f"error (deg) and the runs that stayed stable.", "",
             "| sensor latency | " + " | ".join(f"drop {d:g} %" for d in drops) + " |",
             "|---|" + "---|" * len(drops)]
    for lat in meta["latency_ms"]:
        row = [f"{lat:g} ms"]
        for drop in drops:
            c = next((c for c in cells if c["latency_ms"] == lat and c["drop_pct"] == drop),
                     None)
            row.append("" if c is None else
                       f"{c['att_rms_mean_deg']:.3f} +- {c['att_rms_std_deg']:.3f} "
                       f"({c['att_max_deg']:.1f}; {c['stable_runs']}/{c['runs']})")
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", f"Command: `{meta['command']}`"]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m silbridge.tools.benchmark.link_table",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("--scenario", default="S1", help="base scenario (default %(default)s)")
    ap.add_argument("--latency-ms", type=float, nargs="+", default=list(LATENCY_MS),
                    help="added sensor latencies, ms (default %(default)s)")
    ap.add_argument("--drop-pct", type=float, nargs="+", default=list(DROP_PCT),
                    help="sensor records dropped, %% (default %(default)s)")
    ap.add_argument("--runs", type=int, default=3,
                    help="seeds 1..N per cell (default %(default)s)")
    ap.add_argument("--duration", type=float, default=30.0,
                    help="simulated seconds per flight (default %(default)s)")
    ap.add_argument("--fault-from", type=float, default=10.0,
                    help="sim time the link faults start (default %(default)s)")
    ap.add_argument("--score-from", type=float, default=15.0,
                    help="sim time scoring starts (default %(default)s)")
    ap.add_argument("--out", default="docs/explanation",
                    help="where the .json and .md go (default %(default)s)")
    a = ap.parse_args(argv)
    raw = scenario_raw(a.scenario)
    rows = [fly_cell(raw, seed, lat, drop, a.duration, a.fault_from, a.score_from)
            for lat in a.latency_ms for drop in a.drop_pct for seed in range(1, a.runs + 1)]
    meta = {"scenario": a.scenario, "runs": a.runs, "duration_s": a.duration,
            "latency_ms": a.latency_ms, "drop_pct": a.drop_pct,
            "fault_from_s": a.fault_from, "score_from_s": a.score_from,
            "stable_max_deg": STABLE_MAX_DEG,
            "command": "python -m silbridge.tools.benchmark.link_table " + " ".join(
                f"--{k.replace('_', '-')} " + (" ".join(f"{x:g}" for x in v)
                                               if isinstance(v, list) else str(v))
                for k, v in vars(a).items())}
    cells = summarise(rows, a.latency_ms, a.drop_pct)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"sil-link-faults-{a.scenario}"
    stem.with_suffix(".json").write_text(json.dumps({"meta": meta, "cells": cells,
                                                     "runs": rows}, indent=1) + "\n")
    stem.with_suffix(".md").write_text(markdown(cells, meta))
    print(markdown(cells, meta))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
