"""`silbridge analyze LOG.mcap`: integrity check, then the paper's metrics from one log.

A log failing the integrity check (tools/logs/integrity.py) is refused: exit
status 2 and one line naming the first problem (with --json the full list is
also printed as one JSON object on stdout). `--force` computes the metrics of
such a log anyway and lists its problems. An unfinished log (a killed run: no
closing summary) or an interrupted run's log is not refused: it is checked and
measured over what it holds, and the report says what is missing at the end
(per channel, where its data ends). Windows are in seconds of sim time.
`--spectrum` prints the IMU's vibration peaks instead (tools/cli/analyze_spectrum.py).
"""

from __future__ import annotations

import argparse
import json

from silbridge.tools.cli import analyze_spectrum
from silbridge.tools.logs.integrity import inspect_log
from silbridge.tools.logs.mcap_log import read_log
from silbridge.tools.benchmark.metrics import Windows, compute_metrics, json_safe

HELP = "check a run log's integrity and compute the paper's metrics (or, with --spectrum, " \
       "its IMU spectra) from it"

# (key, label, format) of the text table, in the order of the paper's Table 1.
_ROWS = [
    ("pwm_pp_us", "PWM peak-to-peak (mean over motors)", "{:.1f} us"),
    ("pwm_pp_max_us", "PWM peak-to-peak (worst motor)", "{:.1f} us"),
    ("sat_pct", "saturation occupancy |u| >= 0.99", "{:.3f} %"),
    ("gyro_noise_dps", "gyro noise after filtering (20 Hz .. Nyquist)", "{:.3f} deg/s"),
    ("gyro_in_noise_dps", "gyro noise as read (20 Hz .. Nyquist)", "{:.3f} deg/s"),
    ("dterm_noise_us", "D-term noise (20 Hz .. Nyquist)", "{:.2f} us"),
    ("motor_noise_us", "motor-output noise (mean over motors)", "{:.2f} us"),
    ("att_rms_deg", "attitude error RMS", "{:.3f} deg"),
    ("att_p95_deg", "attitude error P95", "{:.3f} deg"),
    ("att_max_deg", "attitude error max", "{:.3f} deg"),
    ("yaw_rate_rad_s", "steady yaw rate (yaw window)", "{:+.4f} rad/s"),
    ("cp_us", "mixer input cp (pitch)", "{:+.2f} us"),
    ("cr_us", "mixer input cr (roll)", "{:+.2f} us"),
    ("cy_us", "mixer input cy (yaw)", "{:+.2f} us"),
    ("throttle_us", "mixer throttle", "{:.1f} us"),
    ("latency_ms", "end-to-end latency P50", "{:.4f} ms"),
    ("latency_p99_ms", "end-to-end latency P99", "{:.4f} ms"),
    ("sensor_latency_ms", "sensor -> FC latency P50", "{:.4f} ms"),
    ("jitter_ms", "loop jitter P99", "{:.4f} ms"),
    ("jitter_p50_ms", "loop jitter P50", "{:.4f} ms"),
    ("loop_period_ms", "loop period (median)", "{:.4f} ms"),
]


class AnalyzeError(Exception):
    """The log is not fit for analysis; the message names the problem."""

    user_facing = True


def _window(text: str):
    return float(text)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("log", help="the .mcap file a run wrote")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    d = Windows()
    for flag, default in (("--warmup", d.warmup), ("--transient", d.transient),
                          ("--analysis", d.analysis), ("--yaw-window", d.yaw)):
        p.add_argument(flag, nargs=2, type=_window, metavar=("A_S", "B_S"), default=default,
                       help=f"window in s of sim time (default {default[0]:g} {default[1]:g})")
    p.add_argument("--max-loss-pct", type=float, default=0.5,
                   help="largest sample loss the integrity check accepts, in %% "
                        "(default %(default)g)")
    p.add_argument("--force", action="store_true",
                   help="compute metrics even for a log that fails the integrity check")
    analyze_spectrum.add_arguments(p)


def run(args: argparse.Namespace) -> int:
    try:
        windows = Windows(warmup=tuple(args.warmup), transient=tuple(args.transient),
                          analysis=tuple(args.analysis), yaw=tuple(args.yaw_window))
    except ValueError as exc:
        raise AnalyzeError(f"{exc}; give each window as START END with END > START") from exc
    log = read_log(args.log)
    report = inspect_log(log, max_loss_pct=args.max_loss_pct)
    if report.problems and not args.force:
        if args.json:
            print(json.dumps({"log": args.log, "ok": False, "problems": report.problems}))
        more = f" (and {len(report.problems) - 1} more problems)" \
            if len(report.problems) > 1 else ""
        raise AnalyzeError(f"{args.log} fails the integrity check: {report.problems[0]}{more}; "
                           "fix the run, or pass --force to analyse it anyway")
    if args.spectrum:
        return analyze_spectrum.run(args, log, windows.analysis, report)
    metrics = compute_metrics(log, windows)
    if args.json:
        print(json.dumps({"log": args.log, "ok": report.ok, "problems": report.problems,
                          "windows": {"warmup": windows.warmup, "transient": windows.transient,
                                      "analysis": windows.analysis, "yaw": windows.yaw},
                          "metrics": json_safe(metrics),
                          "integrity": json_safe_report(report.as_dict())}))
        return 0
    _print_table(args.log, log, report, metrics)
    return 0


def json_safe_report(report: dict) -> dict:
    """Integrity figures with NaN as None."""
    report["channels"] = {k: json_safe(v) for k, v in report["channels"].items()}
    return report


def _fmt(value, fmt: str) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "n/a"
    return fmt.format(value)


def _print_table(path: str, log, report, m: dict) -> None:
    scen = (log.metadata.get("scenario") or {}).get("name", "?")
    print(f"{path}: scenario {scen}, {m['log_end_s']:.1f} s of sim time, "
          f"integrity {'ok' if report.ok else 'FAILED (forced)'}")
    for p in report.problems:
        print(f"  problem: {p}")
    for n in report.notes:
        print(f"  note: {n}")
    if report.unfinished:
        planned = report.unfinished["planned_s"]
        print(f"  missing at the end (of {planned:g} s planned):" if planned else
              "  missing at the end:")
        for name, c in report.unfinished["channels"].items():
            gone = "" if c["missing_s"] is None else f", {c['missing_s']:.3f} s missing"
            print(f"    {name:<12} data ends at {c['last_s']:.3f} s{gone}")
    print("  channels: " + ", ".join(f"{k} {v.rows}" for k, v in report.channels.items()))
    print(f"  analysis window {m['analysis_start_s']:g}-{m['analysis_end_s']:g} s, "
          f"yaw window {m['yaw_start_s']:g}-{m['yaw_end_s']:g} s")
    if m["window_note"]:
        print(f"  note: {m['window_note']}")
    width = max(len(label) for _, label, _ in _ROWS)
    for key, label, fmt in _ROWS:
        print(f"  {label:<{width}}  {_fmt(m.get(key), fmt)}")
