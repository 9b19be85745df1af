"""`silbridge shm-bench`: two-process micro-benchmark of the shared-memory ring.

Prints streamed records/s (single-record Python calls and numpy batches),
ping-pong round trips/s with round-trip p50/p99, paced 1 kHz one-way
latency p50/p99/max, and the C loops' figures beside them (the ring's own
ceiling). The work is in silbridge.shm.bench; this module only formats.
"""

from __future__ import annotations

import json

HELP = "micro-benchmark of the shared-memory ring between two processes"

# The targets on the reference 2-core machine, printed beside the figures.
TARGETS = {
    "stream_records_per_s": 1_500_000,
    "batch_records_per_s": 50_000_000,
    "pingpong_round_trips_per_s": 400_000,
}
TARGET_ONE_WAY_P50_NS = 2_000


def add_arguments(parser) -> None:
    parser.add_argument("--seconds", type=float, default=1.0,
                        help="duration of each of the 8 phases [s] (default %(default)g)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def _us(ns) -> str:
    return "n/a" if ns is None else f"{ns / 1000:.2f} us"


def _rate_line(label: str, value: float, target: float | None) -> str:
    goal = f"   (target >= {target:,.0f})" if target else ""
    return f"  {label:<34} {value:>16,.0f}{goal}"


def run(args) -> int:
    from silbridge.shm import bench

    res = bench.run(seconds=args.seconds)
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"silbridge shm-bench: two processes, {args.seconds:g} s per phase")
    print(_rate_line("Python single-record records/s", res["stream_records_per_s"],
                     TARGETS["stream_records_per_s"]))
    print(_rate_line("Python numpy-batch records/s", res["batch_records_per_s"],
                     TARGETS["batch_records_per_s"]))
    print(_rate_line("Python ping-pong round trips/s", res["pingpong_round_trips_per_s"],
                     TARGETS["pingpong_round_trips_per_s"]))
    print(f"  {'  round trip p50 / p99':<34} {_us(res['rtt_ns']['p50'])} / "
          f"{_us(res['rtt_ns']['p99'])}")
    print(f"  paced 1 kHz one-way latency p50 / p99 / max (target p50 <= "
          f"{_us(TARGET_ONE_WAY_P50_NS)}):")
    for label, key in (("consumer spinning", "one_way_ns"),
                       ("consumer yielding", "one_way_yield_wait_ns"),
                       ("default wait policy", "one_way_default_wait_ns")):
        ow = res[key]
        print(f"  {'  ' + label:<34} {_us(ow['p50'])} / {_us(ow['p99'])} / {_us(ow['max'])}")
    print(_rate_line("C stream records/s (batch 64)", res["c_stream_records_per_s"], None))
    print(_rate_line("C ping-pong round trips/s", res["c_pingpong_round_trips_per_s"], None))
    print(f"  {'  C round trip p50 / p99':<34} {_us(res['c_rtt_ns']['p50'])} / "
          f"{_us(res['c_rtt_ns']['p99'])}")
    print(f"  overwritten {res['overwritten']}, rejected {res['rejected']}, "
          f"errors {res['errors']} (records checked: {res['records_checked']})")
    return 0 if res["errors"] == 0 else 1
