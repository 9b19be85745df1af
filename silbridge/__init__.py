"""silbridge: high-rate software-in-the-loop for multirotor flight control, from Python.

    import silbridge

    flight = silbridge.fly(scenario="S1", duration_s=30.0,
                           params={"ATC_RAT_RLL_P": 0.2})
    print(flight.metrics["att_rms_deg"], flight.crashed)

    tables = silbridge.bench(scenarios=["S1"], runs=2, duration_s=60.0, out_dir="bench-out")
    print(tables.markdown)

    sc = silbridge.load_scenario("S3", seed=7, **{"imu.rate_hz": 8000})
    log = silbridge.read_log("run.mcap")

The names below are what the `silbridge` command does, as functions that return
typed results instead of printing:

- `fly(**options) -> Flight`: one closed-loop flight (`silbridge fly`); its summary,
  log path and the paper's metrics computed from its log.
- `bench(...) -> BenchResult`: the paper's campaign (`silbridge bench`); Table 1 as
  `silbridge bench --json` prints it, the Markdown tables, the report's index page.
- `load_scenario(name_or_path, seed=None, **overrides) -> Scenario`: a scenario,
  validated, with its random values drawn.
- `read_log(path) -> RunLog`: a run's MCAP log read back (channels as numpy arrays).
- `FlightOptions`, `Windows`: the option and window types those take.
- `__version__`: the installed distribution's version.

Everything is imported on first use, so `import silbridge` costs nothing: the
subpackages (`silbridge.bridge`, `silbridge.fc_sil`, ...) import this package too, in
every process they run in.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:   # what the lazy names are, for type checkers and IDEs
    from silbridge._bench import BenchResult, bench
    from silbridge._flight import Flight, fly
    from silbridge._scenario import load_scenario
    from silbridge.bridge.scenario import Scenario
    from silbridge.tools.benchmark.metrics import Windows
    from silbridge.tools.logs.log_reader import RunLog, read_log
    from silbridge.tools.loop.flight import FlightOptions

    __version__: str

# public name -> the module that defines it (imported on first access)
_LAZY = {
    "fly": "silbridge._flight",
    "Flight": "silbridge._flight",
    "bench": "silbridge._bench",
    "BenchResult": "silbridge._bench",
    "load_scenario": "silbridge._scenario",
    "read_log": "silbridge.tools.logs.log_reader",
    "FlightOptions": "silbridge.tools.loop.flight",
    "Windows": "silbridge.tools.benchmark.metrics",
    "Scenario": "silbridge.bridge.scenario",
    "RunLog": "silbridge.tools.logs.log_reader",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name == "__version__":      # the one lookup `silbridge --version` prints too
        from silbridge.tools.version import package_version
        value = package_version()
    elif name in _LAZY:
        from importlib import import_module
        value = getattr(import_module(_LAZY[name]), name)
    else:
        # AttributeError also lets `from silbridge import tools` import the subpackage.
        raise AttributeError(f"module 'silbridge' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
