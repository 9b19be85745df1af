"""`silbridge speed`: the lockstep's speed beside bare JSBSim (and ArduCopter's own physics),
from one interleaved run, with the spread over the runs and issue 25's targets beside the
ratios. The work is in tools/speed/; this module parses and prints.
"""

from __future__ import annotations

import json
import sys

HELP = ("speed benchmark: bare JSBSim, our one- and two-process lockstep (with and without "
        "a log), ArduCopter's own physics, and the ratios between them")

IMU_HZ_CASE = 32000     # the high-rate IMU case, `--imu-hz` without a value


def add_arguments(p) -> None:
    p.add_argument("--runs", type=int, default=5, metavar="N",
                   help="runs of each case, interleaved (default %(default)s)")
    p.add_argument("--duration", type=float, default=20.0, metavar="S",
                   help="simulated seconds per run (default %(default)g)")
    p.add_argument("--imu-hz", type=int, nargs="?", const=IMU_HZ_CASE, default=None,
                   metavar="N", help=f"also fly both lockstep modes with the IMU at N Hz "
                   f"(no value: {IMU_HZ_CASE}); its ratio to bare JSBSim has no target")
    p.add_argument("--arducopter", default=None, metavar="PATH",
                   help="ArduCopter SITL binary for its own-physics case (default "
                        "$SILBRIDGE_ARDUCOPTER, then `arducopter` on PATH; none: skipped)")
    p.add_argument("--campaign", type=int, nargs="?", const=2, default=None, metavar="N",
                   help="also run the bench's campaign, N runs of each of S1..S4 (no value: 2) "
                        "of --duration, on 1 and on 2 jobs: its overall speed over a single "
                        "run's")
    p.add_argument("--json", action="store_true", help="print one JSON object")


class SpeedOptionError(Exception):
    user_facing = True


def run(args) -> int:
    from silbridge.tools.autopilots.ardupilot.sitl import find_arducopter
    from silbridge.tools.docs.results_page import NO_ARDUCOPTER
    from silbridge.tools.speed.rounds import measure

    if args.runs < 1:
        raise SpeedOptionError("--runs must be at least 1")
    if args.campaign is not None and args.campaign < 1:
        raise SpeedOptionError("--campaign must be at least 1 run of each scenario")
    if not args.duration > 0:
        raise SpeedOptionError("--duration must be > 0 simulated seconds")
    binary = find_arducopter(args.arducopter)
    skipped = {} if binary else {"arducopter": NO_ARDUCOPTER}
    res = measure(args.duration, args.runs, imu_hz=args.imu_hz, arducopter=binary,
                  campaign=args.campaign, skipped=skipped,
                  progress=lambda s: print(s, file=sys.stderr))
    if args.json:
        print(json.dumps(res))
    else:
        print_report(res)
    return 0


def _num(v, fmt: str) -> str:
    return "-" if v is None else fmt.format(v)


def print_report(res: dict, out=print) -> None:
    out(f"silbridge speed: {res['scenario']}, {res['duration_s']:g} s simulated per run, "
        f"{res['runs']} run(s) of each case interleaved, physics {res['physics_hz'] / 1000:g} kHz")
    out(f"{'case':<34} {'x real time':>11} {'min-max':>13} {'worst':>6} {'wall us':>8} "
        f"{'loop_cpu_s':>10} {'cpu us':>7} {'/JSBSim':>8} {'/ArduCopter':>11}")
    for name in res["order"]:
        c = res["cases"][name]
        x, cpu, cpu_step = c["realtime_factor"], c["loop_cpu_s"], c["cpu_us_per_step"]
        span = f"{x['min']:.1f}-{x['max']:.1f}"
        out(f"{c['label']:<34} {x['median']:>11.1f} {span:>13} "
            f"{-100 * c['worst_below_median']:>5.0f}% "
            f"{c['wall_us_per_step']['median']:>8.2f} "
            f"{_num(cpu and cpu['median'], '{:.3f}'):>10} "
            f"{_num(cpu_step and cpu_step['median'], '{:.2f}'):>7} "
            f"{c['of_jsbsim']:>8.2f} {_num(c['of_arducopter'], '{:.2f}'):>11}")
    for name in ("campaign1", "campaign2"):
        if name in res["cases"]:
            c = res["cases"][name]
            out(f"{c['label']:<34} {c['of_single_run']:.2f}x a single run "
                f"({c['single_run_x']:.1f}x: the 1-job campaign's runs, median); workers "
                f"flying {100 * c['flying']:.0f} % of the time, "
                f"{1e3 * c['outside_flight_s']:.0f} ms a run outside its flight")
    for name, why in res["skipped"].items():
        out(f"{name}: skipped: {why}")
    for name in res["order"]:
        nodes = res["cases"][name].get("jsbsim_nodes", "c")
        if nodes != "c":     # the same values, a slower step: the figures must say it
            out(f"{res['cases'][name]['label']}: JSBSim's nodes through their Python methods "
                f"({nodes})")
    out("medians; worst: the slowest run below the median; wall/cpu us: per physics step; "
        "loop_cpu_s: the bridge loop thread (one process: the FC's too)")
    if res["targets"]:
        out("issue 25's targets (measured / target; a benchmark, not a pass/fail):")
    for t in res["targets"]:
        label = res["cases"][t["case"]]["label"]
        if t["figure"] == "of_jsbsim":
            what, fmt = "of bare JSBSim", "{:.2f}"
        elif t["figure"] == "of_single_run":
            what, fmt = "of a single run", "{:.2f}"
        else:
            what, fmt = "worst below median", "{:.1%}"
        out(f"  {label:<34} {what:<20} {fmt.format(t['measured']):>5} / {t['op']} "
            f"{fmt.format(t['target'])}  {'met' if t['met'] else 'not met'}")
