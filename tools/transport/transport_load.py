"""How much CPU other processes took while a transport step was measured.

The comparison runs on two cores that other jobs share. A step that fails far below its rate
on an idle machine has met the transport's ceiling and is not worth a second second; one that
fails while something else held a core may not have. OthersCpu tells the two apart: the
machine's busy time (/proc/stat) minus what the step's own processes used (/proc/PID/stat),
in cores (1.0 = one whole core taken by others over the step). Kernel work done for our own
sockets outside our process context shows up as others' too, so the threshold that uses
this (transport_bench.RETRY_OTHERS_CORES) sits well above the idle-machine figure.
"""

from __future__ import annotations

import os
import time

_TICK_S = 1.0 / os.sysconf("SC_CLK_TCK")


def machine_busy_s() -> float:
    """CPU seconds all cores spent busy since boot (everything but idle and iowait)."""
    with open("/proc/stat") as fh:
        fields = fh.readline().split()[1:]
    ticks = [int(x) for x in fields[:8]]        # user nice system idle iowait irq softirq steal
    return (sum(ticks) - ticks[3] - ticks[4]) * _TICK_S


def process_cpu_s(pid: int) -> float:
    """User + system CPU seconds of one process (0.0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            raw = fh.read()
    except OSError:
        return 0.0
    fields = raw[raw.rindex(")") + 2:].split()   # the command name may hold spaces
    return (int(fields[11]) + int(fields[12])) * _TICK_S


class OthersCpu:
    """start() before a step, cores() after it: the CPU others took, in cores."""

    def __init__(self, pids: list[int]):
        self.pids = list(pids)
        self._t0 = self._busy0 = self._ours0 = 0.0

    def _ours(self) -> float:
        return sum(process_cpu_s(p) for p in self.pids)

    def start(self) -> None:
        self._t0 = time.monotonic()
        self._busy0 = machine_busy_s()
        self._ours0 = self._ours()

    def cores(self) -> float:
        wall = max(time.monotonic() - self._t0, 1e-3)
        others = (machine_busy_s() - self._busy0) - (self._ours() - self._ours0)
        return max(0.0, others) / wall
