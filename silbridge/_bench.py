"""`silbridge.bench`: the paper's campaign, as `silbridge bench --json` runs it.

The campaign, its Table 1, the Markdown tables and the report are the command's
(tools/cli/cmd_bench.py over tools/benchmark/): this module turns keyword arguments
into that command's flags, parses them with the command's own parser (so every default
and check is the command's), runs it with its stdout captured, and reads back the JSON
object it prints and the files it writes.
"""

from __future__ import annotations

import argparse
import contextlib
import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any


class BenchArgumentError(ValueError):
    """An argument `silbridge bench` refuses (the message is its parser's)."""

    user_facing = True


class _Parser(argparse.ArgumentParser):
    """The command's parser, raising where the command line would print and exit."""

    def error(self, message: str):
        raise BenchArgumentError(f"bench: {message}")


@dataclass(frozen=True)
class BenchResult:
    """What a campaign gave.

    table: Table 1 as `silbridge bench --json` prints it (and `table1.json` holds):
        "scenarios" -> per scenario column, each metric's mean and standard deviation
        over the runs; also runs, duration_s, wall_s, params, ...
    """

    table: dict[str, Any]
    markdown: str              # table1.md: Table 1 and the two-way attitude scoring
    out_dir: Path              # the folder with table1.md, table1.json, logs/, report/
    report: Path | None        # report/index.html (None with report=False)
    exit_code: int             # the command's: 0, or 128 + signal if it was interrupted


def bench(scenarios: Sequence[str] | None = None, *, runs: int | None = None,
          duration_s: float | None = None, params: Mapping[str, float] | None = None,
          param_file: str | Path | None = None, seed: int | None = None,
          jobs: int | None = None, fc: Sequence[str] | None = None,
          out_dir: str | Path | None = None, report: bool = True,
          flags: Sequence[str] = ()) -> BenchResult:
    """Run the paper's campaign (Table 1) and return its tables.

    Every argument left as None takes `silbridge bench`'s default (`silbridge bench
    --help`: S1..S4, 20 runs of 120 s, out_dir bench-out, ...).

    scenarios: names ("S1") or TOML files. runs: runs per scenario. duration_s:
        simulated seconds per run. params: FC parameters for every run of our FC.
        param_file: an ArduPilot .parm file read for every run. seed: seed of run 0
        (run i uses seed + i). jobs: parallel runs. fc: "ours", "ardupilot", "px4".
    report: write report/ (plots and index.html).
    flags: any other `silbridge bench` flags, e.g. ``["--keep-logs", "all"]``.

    Progress goes to stderr. Raises the command's user-facing errors (``user_facing``).
    """
    from silbridge.tools.cli import cmd_bench
    from silbridge.tools.loop.flight import last_json_line

    argv = _flags(scenarios=scenarios, runs=runs, duration_s=duration_s, params=params,
                  param_file=param_file, seed=seed, jobs=jobs, fc=fc, out_dir=out_dir,
                  report=report) + [*flags, "--json"]
    parser = _Parser(prog="silbridge bench")
    cmd_bench.add_arguments(parser)
    args = parser.parse_args(argv)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = int(cmd_bench.run(args) or 0)
    out = Path(args.out)
    index = out / "report" / "index.html"
    md = out / "table1.md"
    return BenchResult(table=last_json_line(printed.getvalue()), out_dir=out,
                       markdown=md.read_text() if md.is_file() else "",
                       report=index if report and index.is_file() else None, exit_code=code)


def _flags(*, scenarios, runs, duration_s, params, param_file, seed, jobs, fc, out_dir,
           report) -> list[str]:
    """The `silbridge bench` flags for the arguments given (None: left to the command)."""
    argv: list[str] = []
    pairs = (("--scenarios", None if scenarios is None else ",".join(map(str, scenarios))),
             ("--runs", runs), ("--duration", duration_s), ("--params", param_file),
             ("--seed", seed), ("--jobs", jobs),
             ("--fc", None if fc is None else ",".join(fc)), ("--out", out_dir))
    for flag, value in pairs:
        if value is not None:
            argv += [flag, str(value)]
    for name, value in (params or {}).items():
        argv += ["--param", f"{name}={float(value)!r}"]
    if not report:
        argv.append("--no-report")
    return argv
