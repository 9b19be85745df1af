"""After a SIGKILL, how much of each stream did the log keep? A diagnostic.

    python -m silbridge.tools.logs.kill_check [--after 4] [--victim fc|bridge|single] [--json]

A real-time logged flight (`silbridge fly --realtime --no-mavlink --log`) runs
for `--after` seconds past its start-up checks, then one of its processes is
SIGKILLed: the FC child (it writes the log; the log is left unfinished), the
bridge parent (the FC notices and closes the log), or the single process of
`--processes 1`. The log is then read back and, per channel, the distance
between the kill and the channel's last row is printed, in seconds of sim time:

    kill_sim = newest /imu row's sim time + (kill wall time - its wall stamp)

(real time: one sim second per wall second; both stamps are CLOCK_MONOTONIC, the
records' wall clock). The target (issue 15) is at most 1 s for every channel,
beyond its own sample period. Also reported: whether `silbridge analyze` accepts
the log without --force, and whether the segment is gone.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_S = 1.0


def start_flight(log: Path, processes: int, instance: str, duration_s: float = 120.0):
    cmd = [sys.executable, "-m", "silbridge.tools", "fly", "--realtime", "--no-mavlink",
           "--duration", str(duration_s), "--processes", str(processes), "--log", str(log),
           "--instance", instance]
    out = open(log.with_suffix(".out"), "w")
    proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    return proc, out


def wait_started(proc, out_path: Path, timeout_s: float) -> bool:
    """True once the flight printed its last start-up check."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if "check drops" in out_path.read_text():
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.05)
    return False


def child_pids(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return [int(x) for x in fh.read().split()]
    except OSError:
        return []


def channel_lags(log_path: Path, kill_wall_ns: int) -> dict:
    """Per channel: last sim time and its distance from the kill [s]."""
    from silbridge.tools.logs.integrity import nominal_rates_hz
    from silbridge.tools.logs.mcap_log import read_log

    log = read_log(log_path)
    imu = log.channels["/imu"]
    kill_sim_s = (int(imu["sim_ns"][-1]) + (kill_wall_ns - int(imu["wall_ns"][-1]))) * 1e-9
    rates = nominal_rates_hz(log)
    lags = {}
    for name, rows in sorted(log.channels.items()):
        if name not in rates or not len(rows):
            continue
        last_s = int(rows["sim_ns"][-1]) * 1e-9
        lag = kill_sim_s - last_s
        lags[name] = {"last_s": last_s, "lag_s": lag, "period_s": 1.0 / rates[name],
                      "ok": lag <= TARGET_S + 1.0 / rates[name]}
    missing = [name for name in rates if name not in log.channels]
    return {"kill_sim_s": kill_sim_s, "channels": lags, "missing_channels": missing,
            "finished": log.end is not None}


def run(victim: str, after_s: float, workdir: Path) -> dict:
    processes = 1 if victim == "single" else 2
    instance = f"killcheck-{os.getpid()}-{victim}"
    log = workdir / f"kill-{victim}.mcap"
    proc, out = start_flight(log, processes, instance)
    try:
        if not wait_started(proc, log.with_suffix(".out"), 90.0):
            raise RuntimeError(f"the flight did not start:\n{log.with_suffix('.out').read_text()}")
        time.sleep(after_s)
        target = proc.pid
        if victim == "fc":
            kids = child_pids(proc.pid)
            if not kids:
                raise RuntimeError("no FC child process found")
            target = kids[0]
        kill_wall_ns = time.monotonic_ns()
        os.kill(target, signal.SIGKILL)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        # The FC (if it survives) finishes the log when it notices the bridge is gone.
        for pid in child_pids(proc.pid):
            os.kill(pid, signal.SIGKILL)
    finally:
        out.close()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    time.sleep(0.5)
    res = channel_lags(log, kill_wall_ns)
    analyze = subprocess.run([sys.executable, "-m", "silbridge.tools", "analyze", str(log),
                              "--json"], capture_output=True, text=True, timeout=120)
    left = os.path.exists(f"/dev/shm/silbridge-{instance}")
    if left:   # a SIGKILLed owner cannot unlink; ours, so reclaim it as the next start would
        from silbridge.shm.leftovers import remove
        remove(instance)
    res.update({"victim": victim, "after_s": after_s, "exit_code": proc.returncode,
                "analyze_exit": analyze.returncode, "segment_left": left, "log": str(log)})
    res["all_within_target"] = all(c["ok"] for c in res["channels"].values()) and \
        not res["missing_channels"]
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--victim", choices=("fc", "bridge", "single", "all"), default="all")
    ap.add_argument("--after", type=float, default=4.0,
                    help="seconds of flight after the start-up checks before the kill")
    ap.add_argument("--dir", default=None, help="where the logs go (default: a temp dir)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    victims = ("fc", "bridge", "single") if args.victim == "all" else (args.victim,)
    workdir = Path(args.dir or tempfile.mkdtemp(prefix="silbridge-killcheck-"))
    workdir.mkdir(parents=True, exist_ok=True)
    results = [run(v, args.after, workdir) for v in victims]
    if args.json:
        print(json.dumps({"target_s": TARGET_S, "runs": results}))
        return 0
    for r in results:
        print(f"SIGKILL {r['victim']} after {r['after_s']:g} s (kill at {r['kill_sim_s']:.3f} s "
              f"sim): log {'finished' if r['finished'] else 'unfinished'}, analyze exit "
              f"{r['analyze_exit']}, segment "
              f"{'left (removed now)' if r['segment_left'] else 'gone'}")
        for name, c in r["channels"].items():
            print(f"  {name:<12} last row {c['last_s']:8.3f} s  {c['lag_s'] * 1e3:7.1f} ms before "
                  f"the kill  {'ok' if c['ok'] else 'OVER 1 s'}")
        for name in r["missing_channels"]:
            print(f"  {name:<12} NO ROWS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
