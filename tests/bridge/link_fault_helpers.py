"""Flights with faults of the SIL link (bridge/link_faults.py), for tests/bridge/test_link_faults*.

A scenario file is S1 with [[failure]] entries appended; `fly_watched` flies it in lockstep
in this process (the real simulator, segment, C core and FC loop) with a sink that records,
for every FC poll, the sim time of the step it closed and the records it consumed, and the
motor command the bridge held after each step.
"""

from __future__ import annotations

import os

import numpy as np

from silbridge.bridge.bridge_driver import prepare_segment, run_bridge
from silbridge.bridge.scenario import SCENARIO_DIR
from silbridge.fc_sil.autoflight import AutoFlight
from silbridge.fc_sil.fc_loop import FcLoop
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.shm import Segment
from silbridge.tools.loop.flight import FlightOptions, bridge_config, make_simulator


def scenario_with(tmp_path, *failures: dict, base: str = "S1") -> str:
    """A scenario file: `base` plus one [[failure]] table per dict."""
    text = (SCENARIO_DIR / f"{base}.toml").read_text()
    for f in failures:
        text += "\n[[failure]]\nunit = \"link\"\n" + "".join(
            f"{k} = {v!r}\n" if isinstance(v, str) else f"{k} = {v}\n" for k, v in f.items())
    path = tmp_path / f"link_{len(list(tmp_path.iterdir()))}.toml"
    path.write_text(text)
    return str(path)


class Watch:
    """The FC's per-cycle sink: (step sim_ns, records) of every poll."""

    def __init__(self):
        self.polls: list[tuple[int, np.ndarray]] = []

    def fc_batch(self, recs, pwm, status, timing) -> None:
        self.polls.append((int(recs["sim_ns"][-1]), recs.copy()))

    def arrivals(self, kind: int) -> np.ndarray:
        """(arrival step sim_ns, sample sim_ns) of every record of a kind the FC consumed."""
        rows = [(t, s) for t, recs in self.polls for s in recs["sim_ns"][recs["kind"] == kind]]
        return np.array(rows, dtype=np.int64).reshape(-1, 2)


def fly_watched(scenario: str, duration_s: float):
    """One lockstep flight in this process, FC polled after each step; returns (Watch,
    BridgeResult)."""
    opts = FlightOptions(scenario=scenario, duration_s=duration_s, processes=1)
    sc, sim = make_simulator(opts)
    cfg = bridge_config(opts, sc)
    name = f"linktest-{os.getpid()}-{id(opts) & 0xFFFF}"
    watch = Watch()
    with Segment.create(name) as seg:
        prepare_segment(seg, sim, cfg)
        with Segment.attach(name) as fc_seg:
            core = FlightCore()
            fc = FcLoop(core, fc_seg, supervisor=AutoFlight(core), sink=watch)
            res = run_bridge(sim, seg, cfg, fc_poll=fc.poll, out=lambda s: None)
    return watch, res
