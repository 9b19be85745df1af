"""The soak run: `silbridge sitl` as its own process, a pymavlink ground station on it, a
sample of the processes, the log and the streams every interval, and the verdict at the end.

The vehicle is the real `silbridge sitl` (tools/cli/cmd_sitl.py), started as a child with
one MAVLink endpoint on a free UDP port, `--params FILE --save-params` and `--log`; nothing
of the flight loop is rebuilt here. It ends with SIGTERM, as Ctrl-C would end it, and its
JSON summary (achieved rates, late steps) joins the result.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from silbridge.tools.soak import procs
from silbridge.tools.soak.client import SoakClient
from silbridge.tools.soak.log_minutes import minutes_from_log
from silbridge.tools.soak.verdict import verdict


class SoakError(Exception):
    """The soak could not run (the vehicle never answered, ...): the message says what to do."""
    user_facing = True


@dataclass
class SoakOptions:
    total_s: float
    out_dir: Path
    sample_s: float = 60.0
    action_s: float = 5.0            # one ground-station action every this many seconds
    scenario: str = "S1"
    processes: int = 2
    start_timeout_s: float = 60.0


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sitl_command(opts: SoakOptions, port: int) -> list[str]:
    out = opts.out_dir
    return [sys.executable, "-m", "silbridge", "sitl", "--scenario", opts.scenario,
            "--processes", str(opts.processes), "--no-default-gcs",
            "--gcs", f"udpout:127.0.0.1:{port}",
            "--params", str(out / "soak.parm"), "--save-params",
            "--log", str(out / "soak.mcap"), "--json"]


def _stream_hz(counts, dt_s: float) -> dict:
    return {k: round(v / dt_s, 2) for k, v in sorted(counts.items())}


def sample_line(s: dict) -> str:
    p = s["procs"]
    rss = "  ".join(f"{n} {v['rss_kb'] / 1024:.1f}" for n, v in p.items())
    fds = "/".join(str(v["fds"]) for v in p.values())
    att = s["streams_hz"].get("ATTITUDE", 0.0)
    lag = "-" if s["clock_lag_ms"] is None else f"{s['clock_lag_ms']:.0f}"
    return (f"t={s['t_s']:6.0f} s  RSS MB {rss}  fds {fds}  log {s['log_mb_per_min']:.1f} "
            f"MB/min  ATTITUDE {att:.1f} Hz  {len(s['streams_hz'])} msg types  "
            f"clock lag {lag} ms  actions {s['actions_ok']} ok {s['actions_failed']} failed")


def run_soak(opts: SoakOptions, out=print) -> dict:
    opts.out_dir.mkdir(parents=True, exist_ok=True)
    log_path = opts.out_dir / "soak.mcap"
    port = free_udp_port()
    client = SoakClient(f"udpin:127.0.0.1:{port}")
    cmd = sitl_command(opts, port)
    out(f"soak: {' '.join(cmd[1:])}")
    with open(opts.out_dir / "sitl.stdout.json", "wb") as so, \
            open(opts.out_dir / "sitl.stderr.log", "wb") as se:
        proc = subprocess.Popen(cmd, stdout=so, stderr=se, start_new_session=True)
        try:
            samples = _soak(opts, proc, client, log_path, out)
        finally:
            _stop(proc)
            client.close()
    summary = _last_json(opts.out_dir / "sitl.stdout.json")
    out("soak: reading per-minute late steps and rates from the log")
    try:
        # Bins of one sample interval: a minute in an hour's run, finer in a short one.
        minutes = minutes_from_log(str(log_path), minute_s=opts.sample_s)
    except Exception as exc:   # noqa: BLE001 - a log we cannot read is a finding, not a crash
        out(f"soak: the log could not be read ({exc})")
        minutes = []
    failed = sum(client.failed.values())
    v = verdict(samples, minutes, opts.total_s, failed)
    return {"total_s": opts.total_s, "sample_s": opts.sample_s, "action_s": opts.action_s,
            "command": cmd, "samples": samples, "minutes": minutes,
            "actions": {"ok": dict(client.ok), "failed": dict(client.failed),
                        "failures": client.failures},
            "params_saved": _param_saved(opts.out_dir / "soak.parm"),
            "vehicle_exit": proc.returncode, "vehicle_summary": summary,
            "log": str(log_path), "log_bytes": _size(log_path), **v}


def _soak(opts: SoakOptions, proc, client: SoakClient, log_path: Path, out) -> list[dict]:
    if not client.wait_vehicle(opts.start_timeout_s):
        raise SoakError(f"the vehicle sent no HEARTBEAT in {opts.start_timeout_s:g} s: see "
                        f"{opts.out_dir / 'sitl.stderr.log'}")
    names: dict[int, str] = {}
    t0 = time.monotonic()
    clock0 = None            # (wall, vehicle ms) when the vehicle's clock was first seen
    client.take_counts()
    samples: list[dict] = []
    last_t, last_bytes = t0, _size(log_path)
    next_action, next_sample = t0, t0 + opts.sample_s
    end = t0 + opts.total_s
    while True:
        now = time.monotonic()
        if clock0 is None and client.boot_ms is not None:
            clock0 = (now, client.boot_ms)
        if proc.poll() is not None:
            raise SoakError(f"the vehicle exited with {proc.returncode} after "
                            f"{now - t0:.0f} s: see {opts.out_dir / 'sitl.stderr.log'}")
        if now >= next_sample:
            size = _size(log_path)
            dt = now - last_t
            lag = None if clock0 is None else \
                (now - clock0[0]) * 1e3 - (client.boot_ms - clock0[1])
            s = {"t_s": round(now - t0, 1), "procs": procs.sample(proc.pid, names),
                 "log_bytes": size, "log_mb_per_min": (size - last_bytes) / 1e6 / dt * 60,
                 "streams_hz": _stream_hz(client.take_counts(), dt),
                 "clock_lag_ms": lag, "actions_ok": sum(client.ok.values()),
                 "actions_failed": sum(client.failed.values())}
            samples.append(s)
            out(sample_line(s))
            last_t, last_bytes = now, size
            next_sample += opts.sample_s
            if next_sample > end + opts.sample_s / 2:
                break                     # that was the last sample, on the end itself
        elif now >= next_action and now < end:
            client.run_next()
            next_action += opts.action_s
        else:
            wake = min(next_action, next_sample) if now < end else next_sample
            client.pump(lambda m: False, max(0.0, wake - now))
    return samples


def _stop(proc) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)      # as Ctrl-C: the log is closed, exit 143
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0


def _last_json(path: Path) -> dict:
    for line in reversed(path.read_text(errors="replace").splitlines()):
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                continue
    return {}


def _param_saved(path: Path) -> dict:
    """The gain the client wrote, as the saved --params file holds it."""
    from silbridge.tools.soak.client import GAIN_PARAM
    try:
        for line in path.read_text().splitlines():
            parts = line.replace(",", " ").split()
            if parts and parts[0] == GAIN_PARAM:
                return {"param": GAIN_PARAM, "value": float(parts[1]),
                        "file_mtime": path.stat().st_mtime}
    except (OSError, ValueError, IndexError):
        pass
    return {"param": GAIN_PARAM, "value": None}
