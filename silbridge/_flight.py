"""`silbridge.fly`: one closed-loop flight, as `silbridge fly` flies it, returned not printed.

A thin layer over tools/loop/flight.py: the options are its `FlightOptions`, the flight
is its `fly_one_process` / `fly_two_processes`, the summary its `fly --json` object. The
metrics are the paper's, computed from the run's log by tools/benchmark/metrics.py as
`silbridge analyze` computes them; a flight that was not asked for a log writes one to
a temporary folder for that, and removes it.
"""

from __future__ import annotations

import dataclasses
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from silbridge.tools.benchmark.metrics import Windows
    from silbridge.tools.loop.flight import FlightOptions


@dataclass(frozen=True)
class Flight:
    """What one flight gave.

    The first fields are the summary's headline (the keys of `silbridge fly --json`);
    `summary` holds all of it (rates, latency, jitter, checks, ...).
    """

    scenario: str                 # the scenario's name
    seed: int                     # the seed it flew with
    sim_s: float                  # simulated seconds flown
    wall_s: float                 # wall-clock seconds it took
    realtime_factor: float        # sim_s / wall_s
    crashed: bool                 # the vehicle hit the ground or left the envelope
    interrupted: str | None       # "SIGINT"/"SIGTERM" if a signal cut the run short
    trace_hash: str               # same seed and inputs: same hash, on any machine
    log_path: str | None          # the run's MCAP log (FlightOptions.log_path), else None
    metrics: dict[str, Any]       # the paper's metrics from the log ({} with metrics=False):
    #                               keys and definitions in tools/benchmark/metrics.py
    summary: dict[str, Any]       # the whole `silbridge fly --json` object

    @classmethod
    def from_summary(cls, summary: dict[str, Any], metrics: dict[str, Any]) -> Flight:
        return cls(scenario=summary["scenario"], seed=summary["seed"], sim_s=summary["sim_s"],
                   wall_s=summary["wall_s"], realtime_factor=summary["realtime_factor"],
                   crashed=summary["crashed"], interrupted=summary.get("interrupted"),
                   trace_hash=summary["trace_hash"], log_path=summary.get("log"),
                   metrics=metrics, summary=summary)


def fly(options: FlightOptions | None = None, /, *, metrics: bool = True,
        windows: Windows | None = None, progress: Callable[[str], None] | None = None,
        **fields: Any) -> Flight:
    """Fly one closed loop and return its summary, log path and metrics.

    options: a `silbridge.FlightOptions`; `fields` set or override its fields by name
        (scenario, duration_s, params, param_file, processes, seed, imu_hz, log_path,
        features_off, lockstep, speed, ...; their defaults are FlightOptions').
        Example: ``fly(scenario="S4", duration_s=60.0, params={"ATC_RAT_RLL_D": 0.004})``.
    metrics: compute the paper's metrics from the run's log (writes a temporary log
        when `log_path` is not given).
    windows: the metric windows (`silbridge.Windows`; default the paper's, as
        `silbridge analyze`); a short flight's windows are cut to it, which
        ``metrics["window_note"]`` says.
    progress: called with each progress line (default: none are shown).

    Raises the command line's user-facing errors (a bad scenario, an unknown parameter,
    ...) as exceptions with ``user_facing = True`` and a message saying what to do.
    """
    from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes

    opts = dataclasses.replace(options or FlightOptions(), **fields)
    out = progress or (lambda line: None)
    run = fly_one_process if opts.processes == 1 else fly_two_processes
    if not metrics:
        return Flight.from_summary(run(opts, out=out), {})
    if opts.log_path is not None:
        summary = run(opts, out=out)
        return Flight.from_summary(summary, _log_metrics(opts.log_path, windows))
    with tempfile.TemporaryDirectory(prefix="silbridge-fly-") as tmp:
        # A log only for the metrics: without the viewable channels, which only Foxglove reads.
        viz_hz = 0.0 if opts.viz_hz is None else opts.viz_hz
        log = str(Path(tmp) / "run.mcap")
        summary = run(dataclasses.replace(opts, log_path=log, viz_hz=viz_hz), out=out)
        found = _log_metrics(log, windows)
    summary.pop("log", None)       # gone with the temporary folder
    return Flight.from_summary(summary, found)


def _log_metrics(path: str, windows: Windows | None) -> dict[str, Any]:
    from silbridge.tools.benchmark.metrics import Windows, compute_metrics
    from silbridge.tools.logs.log_reader import read_log

    return compute_metrics(read_log(path), windows or Windows())
