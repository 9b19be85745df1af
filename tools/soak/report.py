"""The soak's figures as a Markdown table, for docs/howto/soak.md.

    python -m silbridge.tools.soak.report /work/soak-1h.json

Reads the JSON `silbridge soak --json` prints (or the soak.json it writes in --out DIR).
"""

from __future__ import annotations

import json
import sys

from silbridge.tools.soak.verdict import baseline_index, median, warmup_s


def _at(samples: list[dict], t_s: float) -> dict:
    """The first sample at or after t_s (the last one if none)."""
    return samples[baseline_index([s["t_s"] for s in samples], t_s)]


def _when(t_s: float) -> str:
    return f"{t_s / 60:.0f} min" if t_s >= 60 else f"{t_s:.0f} s"


def table(r: dict) -> str:
    samples, minutes = r["samples"], r["minutes"]
    first, last = samples[0], samples[-1]
    warm = _at(samples, warmup_s(r["total_s"]))
    rows = [("run", f"{r['total_s'] / 60:.0f} min of `silbridge sitl` (real time), "
                    f"{len(samples)} samples every {r['sample_s']:g} s")]
    for name in first["procs"]:
        rss = [s["procs"][name]["rss_kb"] / 1024 for s in samples if name in s["procs"]]
        rows.append((f"RSS {name} (start / {_when(warm['t_s'])} / end / peak)",
                     f"{rss[0]:.1f} / {warm['procs'][name]['rss_kb'] / 1024:.1f} / "
                     f"{rss[-1]:.1f} / {max(rss):.1f} MB"))
        fds = sorted({s["procs"][name]["fds"] for s in samples if name in s["procs"]})
        rows.append((f"open fds {name}", " .. ".join(map(str, (fds[0], fds[-1])))
                     if len(fds) > 1 else str(fds[0])))
    mb = [s["log_mb_per_min"] for s in samples]
    rows.append(("log growth (median / max)", f"{median(mb):.1f} / {max(mb):.1f} MB/min; "
                                              f"{r['log_bytes'] / 1e9:.2f} GB in all"))
    if minutes:
        late = [m["late_steps_per_min"] for m in minutes]
        imu = [m["imu_hz"] for m in minutes]
        pwm = [m["pwm_hz"] for m in minutes]
        rows.append(("IMU samples the FC consumed, per interval (min / median)", f"{min(imu):.1f} / "
                                                           f"{median(imu):.1f} Hz"))
        rows.append(("PWM the FC published, per interval (min / median)", f"{min(pwm):.1f} / "
                                                           f"{median(pwm):.1f} Hz"))
        rows.append(("late steps per minute (median / max)", f"{median(late):.0f} / "
                                                             f"{max(late):.0f}"))
    vs = r.get("vehicle_summary") or {}
    if vs:
        rh = vs.get("rates_hz", {})
        rows.append(("vehicle summary", f"IMU {rh.get('imu', 0):.1f} Hz, PWM "
                                        f"{rh.get('pwm', 0):.1f} Hz, late steps "
                                        f"{vs.get('late_steps')} in {vs.get('wall_s', 0):.0f} s"))
    if isinstance(vs.get("rates"), dict):     # the real-time rate report, where the run has it
        rows.append(("vehicle rate report", ", ".join(f"{k} {v}"
                                                      for k, v in vs["rates"].items())))
    streams = last["streams_hz"]
    rows.append(("client stream rates, last sample",
                 ", ".join(f"{k} {v:g}" for k, v in streams.items()
                           if k in ("ATTITUDE", "RAW_IMU", "SERVO_OUTPUT_RAW",
                                    "GLOBAL_POSITION_INT", "SYS_STATUS", "HEARTBEAT"))
                 + " Hz"))
    a = r["actions"]
    rows.append(("ground-station actions", f"{sum(a['ok'].values())} ok, "
                                           f"{sum(a['failed'].values())} failed ("
                 + ", ".join(f"{k} {v}" for k, v in a["ok"].items()) + ")"))
    for c in r["checks"]:
        rows.append((f"check {c['name']}", f"{'ok' if c['ok'] else 'FAIL'}: {c['detail']}"))
    rows.append(("verdict", "PASS" if r["ok"] else "FAIL"))
    out = ["| figure | value |", "|---|---|"]
    out += [f"| {k} | {v.replace('|', '/')} |" for k, v in rows]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m silbridge.tools.soak.report SOAK.json", file=sys.stderr)
        return 2
    with open(argv[0]) as f:
        print(table(json.load(f)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
