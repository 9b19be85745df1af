"""Where a lockstep step's wall time goes: one `silbridge fly` under `perf record`, its
samples sorted into the parts of a step by the native call stack each one was taken in.

Instruction counts (callgrind, docs/howto/speed.md) are steady on a shared machine but blind
to what the clock sees: cache misses, a bridge waiting for its FC, Python's low instructions
per cycle. A sampling profile is the clock's own account. `perf record -e cpu-clock` (a
software event: it works in a VM without hardware counters) samples every process of the
flight with its stack (DWARF unwinding: our extensions and the wheels keep no frame pointers);
the samples of the lockstep loop's thread, the span between the first and the last sample
inside `Kernel.run_batch`, are counted by part (`PARTS`, first match wins). In two processes
the FC's process is reported on its own: how much of its time it computes, how much it waits;
the bridge's other threads (a MAVLink server's, numpy's) are counted beside the loop,
not in its parts.

    python -m silbridge.tools.speed.clock_budget [--processes 1|2] [--duration S] [--json]

Needs `perf` (Debian: `apt-get install linux-perf`) allowed to sample its own children
(kernel.perf_event_paranoid <= 2, the default). perf slows the flight (its own figure is
printed); the shares are what it measures, not the speed.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

from silbridge.tools.loop.flight import last_json_line

SAMPLE_HZ = 1500
LOOP_MARK = "Kernel_run_batch"      # the C batch: a sample under it is inside the loop
# (part, where, names any of which in the stack puts a sample there); where: "batch" under
# LOOP_MARK, "outside" not, "any" either. First match wins: JSBSim's run() before the
# getters (both are JSBSim code), the hash before the batch's other work.
PARTS = [
    ("JSBSim run()", "batch", ("JSBSim::FGFDMExec::Run",)),
    ("the FC's step (one process)", "batch", ("Core_poll_io", "fc_ext_run_records")),
    ("waiting for the FC's answer", "batch", ("sb_handoff_wait",)),
    ("trace hash", "any", ("sb_blake2b_update", "Blake2b_update")),
    ("JSBSim getters and setters", "batch", ("sb_call0", "sb_call1", "read_sample",
                                             "write_pwm")),
    ("sensor stage", "batch", ("sb_sensor_stage_step",)),
    ("batch: rings, words, clock", "batch", ()),
    ("noise draws (numpy)", "outside", ("random_standard_normal", "_pcg64")),
    ("Python between batches", "outside", ()),
]
FC_WAIT = ("sb_handoff_wait", "records_ready", "sb_cpu_relax")


class ClockBudgetError(Exception):
    user_facing = True


def parse_samples(text: str) -> list[tuple[int, int, float, list[str]]]:
    """`perf script -F pid,tid,time,ip,sym,dso` -> [(pid, tid, time_s, [symbol, ...
    outward])]."""
    samples, cur = [], None
    head = re.compile(r"\s*(\d+)/(\d+)\s+([\d.]+):\s*(.*)$")
    frame = re.compile(r"\s*[0-9a-f]+ (.*) \(.*\)$")
    for line in text.splitlines():
        if not line.strip():
            if cur is not None:
                samples.append(cur)
            cur = None
            continue
        m = head.match(line)
        if m and cur is None:
            cur = (int(m.group(1)), int(m.group(2)), float(m.group(3)), [])
            rest = frame.match(m.group(4))
            if rest:
                cur[3].append(rest.group(1))
            continue
        m = frame.match(line)
        if m and cur is not None:
            cur[3].append(m.group(1))
    if cur is not None:
        samples.append(cur)
    return samples


def part_of(stack: list[str]) -> str:
    """The part of a step a sample of the bridge's loop belongs to (PARTS)."""
    inside = any(f.startswith(LOOP_MARK) for f in stack)
    for name, where, marks in PARTS:
        if (where == "batch" and not inside) or (where == "outside" and inside):
            continue
        if not marks or any(m in f for f in stack for m in marks):
            return name
    return "Python between batches"


def budget(samples: list[tuple[int, int, float, list[str]]]) -> dict:
    """Shares of the loop thread's samples per part, for the bridge and (two processes) the
    FC; the bridge's other threads as a count beside the loop's."""
    marked = [((p, tid), t) for p, tid, t, s in samples
              if any(f.startswith(LOOP_MARK) for f in s)]
    if not marked:
        raise ClockBudgetError("no sample inside the lockstep batch: did the flight run? "
                               "(perf may have lost its stacks: try a longer --duration)")
    bridge, loop_tid = Counter(k for k, _ in marked).most_common(1)[0][0]
    t0, t1 = min(t for _, t in marked), max(t for _, t in marked)
    loop = [(p, tid, s) for p, tid, t, s in samples if t0 <= t <= t1]
    parts = Counter(part_of(s) for p, tid, s in loop if (p, tid) == (bridge, loop_tid))
    total = sum(parts.values())
    beside = sum(1 for p, tid, _ in loop if p == bridge and tid != loop_tid)
    out = {"loop_s": t1 - t0, "bridge_samples": total, "beside_loop_samples": beside,
           "bridge": {name: parts.get(name, 0) / total for name, _, _ in PARTS}}
    others = [s for p, _, s in loop if p != bridge]
    if others:
        waiting = sum(1 for s in others if any(w in f for f in s for w in FC_WAIT))
        out["fc_samples"] = len(others)
        out["fc"] = {"waiting for the bridge": waiting / len(others),
                     "computing": 1 - waiting / len(others)}
    return out


def _perf() -> str:
    perf = shutil.which("perf")
    if perf is None:
        raise ClockBudgetError("perf is not installed: on Debian `apt-get install linux-perf`")
    probe = subprocess.run([perf, "record", "-q", "-e", "cpu-clock", "-o", "/dev/null", "true"],
                           capture_output=True, text=True)
    if probe.returncode != 0:
        tail = (probe.stderr.strip().splitlines() or ["no output"])[-1]
        raise ClockBudgetError(f"perf cannot sample here ({tail}); allow it with "
                               "`sysctl kernel.perf_event_paranoid=2` or run as root")
    return perf


def measure(processes: int, duration_s: float, scenario: str = "S1") -> dict:
    perf = _perf()
    with tempfile.TemporaryDirectory(prefix="silbridge-clock-") as tmp:
        data = str(Path(tmp) / "perf.data")
        fly = [sys.executable, "-m", "silbridge", "fly", "--processes", str(processes),
               "--scenario", scenario, "--duration", f"{duration_s:g}", "--json"]
        done = subprocess.run([perf, "record", "-q", "-e", "cpu-clock", "-F", str(SAMPLE_HZ),
                               "--call-graph", "dwarf,16384", "-o", data, "--", *fly],
                              capture_output=True, text=True)
        summary = last_json_line(done.stdout)
        if done.returncode != 0 or not summary:
            tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
            raise ClockBudgetError(f"the flight under perf failed ({tail}); run it alone: "
                                   f"{' '.join(fly[2:])}")
        script = subprocess.run([perf, "script", "-i", data, "-F", "pid,tid,time,ip,sym,dso"],
                                capture_output=True, text=True)
    out = budget(parse_samples(script.stdout))
    out.update(processes=processes, scenario=scenario, duration_s=duration_s,
               realtime_factor_under_perf=summary["realtime_factor"],
               trace_hash=summary.get("trace_hash"))
    return out


def _print(r: dict) -> None:
    print(f"silbridge clock budget: fly --processes {r['processes']} --scenario {r['scenario']} "
          f"--duration {r['duration_s']:g}, {r['bridge_samples']} samples of the bridge's loop "
          f"({r['realtime_factor_under_perf']:.1f}x real time under perf)")
    for name, share in r["bridge"].items():
        if share > 0:
            print(f"  {name:32s} {100 * share:5.1f} %")
    if r["beside_loop_samples"]:
        print(f"the bridge's other threads: {r['beside_loop_samples']} "
              f"samples, {100 * r['beside_loop_samples'] / r['bridge_samples']:.1f} % of the "
              f"loop's")
    if "fc" in r:
        print(f"the FC's process ({r['fc_samples']} samples): computing "
              f"{100 * r['fc']['computing']:.1f} %, waiting for the bridge "
              f"{100 * r['fc']['waiting for the bridge']:.1f} %")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m silbridge.tools.speed.clock_budget",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--processes", type=int, choices=(1, 2), default=1,
                    help="the FC in the loop's process (1) or in its own (2) "
                         "(default %(default)s)")
    ap.add_argument("--duration", type=float, default=60.0, metavar="S",
                    help="simulated seconds (default %(default)s)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args(argv)
    try:
        r = measure(a.processes, a.duration)
    except ClockBudgetError as exc:
        print(f"clock_budget: {exc}", file=sys.stderr)
        return 2
    if a.json:
        print(json.dumps(r))
    else:
        _print(r)
    return 0


if __name__ == "__main__":
    sys.exit(main())
