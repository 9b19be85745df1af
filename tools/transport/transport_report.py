"""Outputs of the transport comparison: the Markdown table in the paper's shape (Table 2, its
figures beside ours), the JSON, and two PNG plots (achieved vs requested IMU rate; sensor ->
FC latency CDF per transport)."""

from __future__ import annotations

import json
import os

# Paper, Table 2 (RPC vs shared memory, Hz).
PAPER = {"imu": (15_516, 78_383), "baro": (100, 100), "mag": (100, 100), "pwm": (340, 400)}
_ROWS = (("imu", "IMU"), ("baro", "Barometer"), ("mag", "Magnetometer"), ("pwm", "PWM"))


def _label(name: str, t: dict) -> str:
    if t["transport"] == "shm":
        return "shm"
    crc = "fastcrc" if t["fastcrc"] else "pure-Python CRC"
    return f"{t['transport']} ({crc})"


def _f(v, fmt="{:,.0f}") -> str:
    return "n/a" if v is None else fmt.format(v)


def markdown(report: dict) -> str:
    ts = report["transports"]
    names = list(ts)
    head = "| | paper RPC | paper SHM | " + " | ".join(_label(n, ts[n]) for n in names) + " |"
    lines = ["Achieved rates (Hz) at each transport's highest passing IMU step "
             "(zero drops, IMU >= 99.5 % of requested, PWM within 0.5 % of 400 Hz).", "",
             head, "|" + "---|" * (3 + len(names))]
    for key, label in _ROWS:
        rpc, shm = PAPER[key]
        cells = [_f(ts[n]["achieved_hz"].get(key)) if ts[n]["achieved_hz"] else "n/a"
                 for n in names]
        lines.append(f"| {label} | {rpc:,} | {shm:,} | " + " | ".join(cells) + " |")
    # A series a busy host ended has no transport ceiling: its last passing step is a floor.
    lines.append("| highest passing IMU step | | | "
                 + " | ".join(_f(ts[n]["max_imu_hz"]) + _ended(ts[n]) for n in names) + " |")
    for q in ("p50", "p95", "p99"):
        lines.append(f"| sensor->FC latency {q} (us) | | | "
                     + " | ".join(_f(ts[n]["latency_us"][q], "{:,.1f}") for n in names) + " |")
    for q in ("p50", "p95", "p99"):
        lines.append(f"| FC loop jitter {q} (us) | | | "
                     + " | ".join(_f(ts[n]["jitter_us"][q], "{:,.1f}") for n in names) + " |")
    lines.append("| drop ratio | | | " + " | ".join(_f(ts[n]["drop_ratio"], "{:.4%}")
                                                   for n in names) + " |")
    for part, label in (("encode", "bridge encode"), ("parse", "FC parse (pymavlink)"),
                        ("to_records", "FC record rebuild")):
        cells = [_f((ts[n].get("codec_us_per_message") or {}).get(part), "{:.2f}")
                 for n in names]
        lines.append(f"| {label} (us per message) | | | " + " | ".join(cells) + " |")
    lines += ["", "Every step (IMU requested -> achieved at the FC):", "",
              "| transport | IMU requested | IMU achieved | baro | mag | PWM | latency p50/p95/p99 "
              "(us) | drop | overwrite | late steps | result |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for n in names:
        for s in ts[n]["steps"]:
            a, lat = s["achieved_hz"], s["latency_us"]
            lines.append(
                f"| {_label(n, ts[n])} | {s['imu_hz_requested']:,} | {_f(a.get('imu'))} | "
                f"{_f(a.get('baro'), '{:.1f}')} | {_f(a.get('mag'), '{:.1f}')} | "
                f"{_f(a.get('pwm'), '{:.1f}')} | {_f(lat['p50'], '{:.0f}')} / "
                f"{_f(lat['p95'], '{:.0f}')} / {_f(lat['p99'], '{:.0f}')} | "
                f"{s['drop_ratio']:.4%} | {s['overwrite_ratio']:.4%} | {s['late_steps']} | "
                f"{_result(s)} |")
    if any(t.get("degraded_steps") for t in ts.values()):
        lines += ["", "degraded: the step missed while other processes used the CPU (a busy "
                  "host, not the transport); a series it ended reads \"at least\" (busy host)."]
    return "\n".join(lines) + "\n"


def _ended(t: dict) -> str:
    return " (at least; busy host)" if t.get("ended_by") == "busy host" else ""


def _result(s: dict) -> str:
    if s["ok"]:
        return "ok"
    return "degraded" if s.get("degraded") else "FAILED"


def preload() -> None:
    """Import the plotting library now (~0.5 s), while the children start, not after the run."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401


def plot_rates(report: dict, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    top = 1000
    for n, t in report["transports"].items():
        req = [s["imu_hz_requested"] for s in t["steps"]]
        got = [s["achieved_hz"].get("imu", 0.0) or 1.0 for s in t["steps"]]
        top = max([top] + req)
        ax.plot(req, got, marker="o", label=_label(n, t))
    ax.plot([1000, top], [1000, top], color="0.6", linestyle=":", label="requested")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("requested IMU rate (Hz)")
    ax.set_ylabel("IMU rate achieved at the FC (Hz)")
    ax.set_title("Transport stress test: IMU rate")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_latency_cdf(report: dict, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for n, t in report["transports"].items():
        steps = [s for s in t["steps"] if s["latency_cdf_us"]]
        if not steps:
            continue
        first = steps[0]
        q = [i / 100 for i in range(len(first["latency_cdf_us"]))]
        line, = ax.plot(first["latency_cdf_us"], q,
                        label=f"{_label(n, t)} @ {first['imu_hz_requested']:,} Hz")
        passed = [s for s in steps if s["ok"]]
        if passed and passed[-1] is not first:
            s = passed[-1]
            ax.plot(s["latency_cdf_us"], q, color=line.get_color(), linestyle="--",
                    label=f"{_label(n, t)} @ {s['imu_hz_requested']:,} Hz")
    ax.set_xscale("log")
    ax.set_xlabel("sensor -> FC latency (us)")
    ax.set_ylabel("fraction of FC polls")
    ax.set_title("Latency CDF (solid: 1 kHz; dashed: highest passing step)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(report: dict, out_dir: str) -> dict:
    os.makedirs(out_dir, exist_ok=True)
    paths = {"json": os.path.join(out_dir, "transport.json"),
             "markdown": os.path.join(out_dir, "transport.md"),
             "imu_rate_png": os.path.join(out_dir, "transport_imu_rate.png"),
             "latency_cdf_png": os.path.join(out_dir, "transport_latency_cdf.png")}
    with open(paths["markdown"], "w") as fh:
        fh.write("# Transport comparison (paper Table 2)\n\n" + markdown(report))
    plot_rates(report, paths["imu_rate_png"])
    plot_latency_cdf(report, paths["latency_cdf_png"])
    with open(paths["json"], "w") as fh:
        json.dump({**report, "outputs": paths}, fh, indent=1)
    return paths
