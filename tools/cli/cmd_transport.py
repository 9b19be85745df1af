"""`silbridge transport`: the transport stress test (paper Table 2) in one run.

IMU stepped from 1 kHz upward per transport (shared memory, MAVLink HIL over UDP and TCP, with
and without pymavlink's fastcrc), baro/mag 100 Hz, PWM 400 Hz, real time, closed loop with the
real FC. Prints the table in the paper's shape; --out DIR also writes JSON, Markdown and PNGs.
The work is in tools/transport/transport_bench.py.
"""

from __future__ import annotations

import json
import sys

from silbridge.tools.cli.aliases import add_deprecated_alias
from silbridge.tools.transport.transport_bench import (
    DEFAULT_DURATION_S,
    DEFAULT_IMU_MAX_HZ,
    DEFAULT_TRANSPORTS,
    VARIANTS,
    TransportBenchConfig,
    run_comparison,
)

HELP = "transport stress test: shared memory vs MAVLink HIL (UDP/TCP), paper Table 2"


def add_arguments(p) -> None:
    p.add_argument("--transports", default=",".join(DEFAULT_TRANSPORTS),
                   help=f"comma-separated, from {', '.join(VARIANTS)} "
                        f"(default {','.join(DEFAULT_TRANSPORTS)}); '-nofastcrc' runs pymavlink "
                        f"with its pure-Python CRC")
    p.add_argument("--imu-max", type=float, default=DEFAULT_IMU_MAX_HZ, metavar="HZ",
                   help="highest IMU step (default %(default)d); steps 1k, 2k, 5k, 10k, ...")
    # Wall seconds, not the simulated seconds --duration means everywhere else: a step that
    # cannot keep up with the wall clock simulates less than it lasts. The old spelling
    # `--duration` (same meaning) stays a hidden alias for one release.
    p.add_argument("--seconds-per-rate", type=float, default=DEFAULT_DURATION_S, metavar="S",
                   help="wall-clock seconds each transport runs at each IMU rate "
                        "(default %(default)g)")
    add_deprecated_alias(p, "--duration", "--seconds-per-rate")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="write transport.json, transport.md and two PNG plots here")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args) -> int:
    from silbridge.tools.transport.transport_bench import TransportBenchError
    if args.seconds_per_rate <= 0:
        raise TransportBenchError("--seconds-per-rate must be > 0")
    cfg = TransportBenchConfig(
        transports=tuple(t.strip() for t in args.transports.split(",") if t.strip()),
        imu_max_hz=int(args.imu_max), duration_s=args.seconds_per_rate, out_dir=args.out)
    from silbridge.tools.loop.stop_signals import STOP
    with STOP.polling():
        report = run_comparison(cfg, out=lambda s: print(s, file=sys.stderr), stop=STOP)
    if args.json:
        slim = {"transports": {n: {k: v for k, v in t.items() if k != "steps"}
                               | {"steps": [{k: v for k, v in s.items() if k != "latency_cdf_us"}
                                            for s in t["steps"]]}
                               for n, t in report["transports"].items()},
                "config": report["config"], "wall_s": report["wall_s"],
                "interrupted": report.get("interrupted")}
        if "outputs" in report:
            slim["outputs"] = report["outputs"]
        print(json.dumps(slim))
    else:
        from silbridge.tools.transport.transport_report import markdown
        if report["transports"]:
            print(markdown(report))
        if "outputs" in report:
            print("wrote " + ", ".join(report["outputs"].values()))
        if report.get("interrupted"):
            print(f"INTERRUPTED by {report['interrupted']}: transports measured: "
                  f"{', '.join(report['transports']) or 'none'}")
    return STOP.exit_code(0)
