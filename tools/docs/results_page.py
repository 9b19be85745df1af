"""docs/results.md, written from a bench run and never by hand.

    python -m silbridge.tools.docs.results_page --bench-out bench-out [--transport DIR]
        [--out docs/results.md] [--arducopter PATH]
    python -m silbridge.tools.docs.results_page --run --bench-out bench-out   # campaign too

The page holds what a reader needs to judge the figures: the machine they came from (with
its load average when this command started), Table 1 as the campaign wrote it
(bench-out/table1.md, its numbers from table1.json), Table 2 from the transport comparison's
transport.json (default: bench-out/transport/, where `make bench` writes it), the campaign's
wall time and real-time factor, and beside them the references measured by this same command
(tools/docs/results_speed.py) with the ratios. `--run` runs the campaign and the transport
comparison first, after the machine is described, so the load average is the campaign's own.
"""

from __future__ import annotations

import argparse
import datetime
import json
import shlex
import subprocess
import sys
from pathlib import Path

from silbridge.tools.docs.machine import describe_machine, machine_rows
from silbridge.tools.docs.markdown_text import cell, code

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = REPO_ROOT / "docs" / "results.md"
PROG = "python -m silbridge.tools.docs.results_page"


NO_ARDUCOPTER = ("no ArduCopter SITL binary: set SILBRIDGE_ARDUCOPTER or give --arducopter "
                 "PATH to this command")


class ResultsPageError(Exception):
    user_facing = True


def load_bench(bench_out: Path) -> tuple[dict, str]:
    """(table1.json, table1.md) of a `silbridge bench --out DIR` run."""
    js, md = bench_out / "table1.json", bench_out / "table1.md"
    if not js.exists() or not md.exists():
        raise ResultsPageError(f"{bench_out} has no table1.json and table1.md: run `silbridge "
                               f"bench --out {bench_out}` first, or add --run")
    return json.loads(js.read_text()), md.read_text().strip()


def written_at(path: Path) -> str:
    t = datetime.datetime.fromtimestamp(path.stat().st_mtime, datetime.timezone.utc)
    return t.strftime("%Y-%m-%d %H:%M UTC")


def load_transport(transport_dir: Path | None) -> dict | None:
    if transport_dir is None:
        return None
    path = transport_dir / "transport.json"
    if not path.exists():
        raise ResultsPageError(f"{path} is missing: run `silbridge transport --out "
                               f"{transport_dir}` first, or leave --transport out")
    return json.loads(path.read_text())


def run_campaign(bench_out: Path, bench_args: str, transport_args: str | None) -> None:
    """`silbridge bench` then `silbridge transport`, as `make bench` runs them."""
    cli = [sys.executable, "-m", "silbridge"]
    steps = [cli + ["bench", "--out", str(bench_out), *shlex.split(bench_args)]]
    if transport_args is not None:
        steps.append(cli + ["transport", "--out", str(bench_out / "transport"),
                            *shlex.split(transport_args)])
    for argv in steps:
        done = subprocess.run(argv, stdout=subprocess.DEVNULL)
        if done.returncode != 0:
            raise ResultsPageError(f"`{shlex.join(argv[3:])}` exited {done.returncode}; "
                                   "fix that run first")


def _x(v: float | None, fmt: str = "{:.1f}") -> str:
    return "n/a" if v is None else fmt.format(v)


def _campaign_lines(table: dict, table_md: str, written: str) -> list[str]:
    scen = sorted({k.partition(" ")[0] for k in table["scenarios"]})
    wall, sim = table.get("wall_s"), table.get("sim_s_total")
    params = ", ".join(f"{k}={v:g}" for k, v in (table.get("params") or {}).items()) or "none"
    return [
        "## Table 1: the campaign", "",
        f"Scenarios {', '.join(scen)}; runs per scenario: {table.get('runs')}, "
        f"{table.get('duration_s'):g} s simulated each; flight controllers: "
        f"{', '.join(table.get('fc', []))}; executor {table.get('executor')}; parameter "
        f"overrides: {cell(params)}. Tables written {written}.", "",
        f"**Wall time {_x(wall)} s** for {_x(sim, '{:.0f}')} s simulated: "
        f"**{_x(sim / wall if wall and sim else None)}x real time** overall.", "",
        table_md, ""]


def _transport_lines(report: dict | None) -> list[str]:
    out = ["## Table 2: transports", ""]
    if report is None:
        return out + ["Not measured in this run: `silbridge transport --out "
                      "bench-out/transport` measures it, and this page then includes it.", ""]
    from silbridge.tools.transport.transport_report import markdown
    cfg = report.get("config", {})
    return out + [
        f"Transports {', '.join(cfg.get('transports', []))}, IMU steps up to "
        f"{max(cfg.get('imu_steps_hz') or [0]):,} Hz; wall time {_x(report.get('wall_s'))} s.",
        "", markdown(report).strip(), ""]


def _speed_lines(table: dict, jsbsim: dict, arducopter: dict | None, why_not: str) -> list[str]:
    from silbridge.tools.docs.results_speed import speed_rows
    rows = speed_rows(table, jsbsim, arducopter)
    out = ["## Speed beside its references", "",
           "The references were measured by the command that wrote this page, on the same "
           "machine, after the campaign. A ratio is the row's real-time factor over the "
           "reference's.", "",
           "| | x real time | ratio to bare JSBSim | ratio to ArduCopter's own physics |",
           "|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['label']} | {_x(r['x'])} | {_x(r['of_jsbsim'], '{:.2f}')} | "
                   f"{_x(r['of_arducopter'], '{:.2f}')} |")
    out += ["", f"Bare JSBSim: {jsbsim['us_per_step']:.2f} us per `run()` (median of "
            f"{jsbsim['blocks']} blocks of {jsbsim['steps']:,} steps, airborne at hover; best "
            f"block {jsbsim['best_realtime_factor']:.1f}x real time)."]
    if arducopter:
        out.append(f"ArduCopter: `{Path(arducopter['binary']).name}`, sim seconds "
                   f"{arducopter['skip_s']:g}-{arducopter['skip_s'] + arducopter['span_s']:g} "
                   "after boot, from its MAVLink `time_boot_ms`.")
    else:
        out.append(f"ArduCopter's own physics: not measured ({why_not}).")
    return out + [""]


def render(machine: dict, table: dict, table_md: str, transport: dict | None, jsbsim: dict,
           arducopter: dict | None, *, why_not: str = "", command: str = PROG,
           written: str = "", ran_campaign: bool = False) -> str:
    head = ["# Results", "",
            "Written by a command from a benchmark run, never by hand; regenerate it with "
            f"{code(command)}. Every figure below depends on the machine, so it comes with "
            "the machine's description and with references measured beside it: compare "
            "ratios across machines, not raw speeds.", "",
            "## The machine", "",
            "Its load average is the one when this page's command started"
            + (", just before it ran the campaign." if ran_campaign else
               "; the campaign ran before it.") + " Other work on the machine "
            "slows every figure below.", "", "| | |", "|---|---|"]
    head += [f"| {cell(k)} | {cell(v)} |" for k, v in machine_rows(machine)]
    lines = (head + [""] + _campaign_lines(table, table_md, written)
             + _transport_lines(transport)
             + _speed_lines(table, jsbsim, arducopter, why_not))
    return "\n".join(lines).rstrip() + "\n"


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    p.add_argument("--bench-out", required=True, metavar="DIR",
                   help="a `silbridge bench --out DIR` folder (table1.json, table1.md)")
    p.add_argument("--transport", default=None, metavar="DIR",
                   help="a `silbridge transport --out DIR` folder (default: DIR/transport "
                        "under --bench-out when it holds transport.json)")
    p.add_argument("--out", default=str(DEFAULT_OUT), metavar="FILE",
                   help="the page to write (default %(default)s)")
    p.add_argument("--arducopter", default=None, metavar="PATH",
                   help="ArduCopter SITL binary for its own-physics reference (default "
                        "$SILBRIDGE_ARDUCOPTER, then `arducopter` on PATH; none: not measured)")
    p.add_argument("--run", action="store_true",
                   help="run the campaign and the transport comparison into --bench-out first")
    p.add_argument("--bench-args", default="", metavar="ARGS",
                   help="with --run: more `silbridge bench` options, one string")
    p.add_argument("--transport-args", default="", metavar="ARGS",
                   help="with --run: more `silbridge transport` options, one string")
    p.add_argument("--no-transport", action="store_true",
                   help="with --run: skip the transport comparison")
    return p


def _transport_dir(args, bench_out: Path) -> Path | None:
    if args.transport:
        return Path(args.transport)
    default = bench_out / "transport"
    return default if (default / "transport.json").exists() else None


def portable_command(argv: list[str]) -> str:
    """The command line as a reader elsewhere would type it: this machine's paths give way
    to the environment variable or the folder's own name (the page goes into the docs)."""
    out, it = [], iter(argv)
    for arg in it:
        flag, eq, value = arg.partition("=")
        if flag in ("--arducopter", "--bench-out", "--transport", "--out"):
            value = value if eq else next(it, "")
            if flag == "--arducopter":
                value = "$SILBRIDGE_ARDUCOPTER"
            elif flag != "--out":
                value = Path(value).name
            out.append(f"{flag} {value}" if flag == "--arducopter" else shlex.join([flag, value]))
            continue
        out.append(shlex.quote(arg))
    return " ".join(out)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = _parser().parse_args(argv)
    bench_out = Path(args.bench_out)
    try:
        machine = describe_machine()           # before anything runs: the load at the start
        if args.run:
            run_campaign(bench_out, args.bench_args,
                         None if args.no_transport else args.transport_args)
        table, table_md = load_bench(bench_out)
        transport = load_transport(_transport_dir(args, bench_out))
        from silbridge.tools.autopilots.ardupilot.sitl import find_arducopter
        from silbridge.tools.docs.jsbsim_speed import measure
        from silbridge.tools.docs.results_speed import measure_arducopter
        jsbsim = measure()
        binary = find_arducopter(args.arducopter)
        arducopter = measure_arducopter(binary) if binary else None
        text = render(machine, table, table_md, transport, jsbsim, arducopter,
                      why_not="" if binary else NO_ARDUCOPTER,
                      written=written_at(bench_out / "table1.json"),
                      command=f"{PROG} {portable_command(argv)}", ran_campaign=args.run)
    except Exception as exc:  # noqa: BLE001 - only user-facing errors are shortened
        if getattr(exc, "user_facing", False):
            print(f"results_page: error: {exc}", file=sys.stderr)
            return 2
        raise
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%H:%M UTC")
    print(f"wrote {out} ({stamp})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
