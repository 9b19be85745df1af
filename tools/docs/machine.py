"""The machine a measurement ran on, as a reader needs it to compare figures: CPU model,
cores, memory, kernel, distribution, Python, JSBSim, silbridge, and the load average when
the measurement started (a busy machine halves a real-time factor). Linux only, as the
project is: everything comes from /proc and /etc/os-release.
"""

from __future__ import annotations

import datetime
import os
import platform
from importlib import metadata


def _first(path: str, key: str) -> str | None:
    """The value of the first 'key: value' line of a /proc-style file."""
    try:
        with open(path) as fh:
            for line in fh:
                name, _, value = line.partition(":")
                if name.strip() == key:
                    return value.strip()
    except OSError:
        return None
    return None


def _os_release() -> str | None:
    try:
        with open("/etc/os-release") as fh:
            for line in fh:
                if line.startswith("PRETTY_NAME="):
                    return line.split("=", 1)[1].strip().strip('"')
    except OSError:
        return None
    return None


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def describe_machine() -> dict:
    """A JSON-able description of this machine now; call it before the measurement starts."""
    mem_kb = _first("/proc/meminfo", "MemTotal")
    load = os.getloadavg()
    return {
        "when_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu_model": _first("/proc/cpuinfo", "model name") or platform.processor() or None,
        "cores_logical": os.cpu_count(),
        "cores_usable": len(os.sched_getaffinity(0)),
        "memory_gib": round(int(mem_kb.split()[0]) / 2**20, 1) if mem_kb else None,
        "kernel": f"{platform.system()} {platform.release()} {platform.machine()}",
        "os": _os_release(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "jsbsim": _version("jsbsim"),
        "silbridge": _version("silbridge"),
        "load_average": [round(x, 2) for x in load],
    }


# (key, label) in the order the page lists them.
LABELS = (
    ("cpu_model", "CPU"),
    ("cores_logical", "logical cores"),
    ("cores_usable", "cores this process may use"),
    ("memory_gib", "memory (GiB)"),
    ("kernel", "kernel"),
    ("os", "distribution"),
    ("python", "Python"),
    ("jsbsim", "JSBSim"),
    ("silbridge", "silbridge"),
    ("load_average", "load average when the command started (1, 5, 15 min)"),
    ("when_utc", "described at"),
)


def machine_rows(machine: dict) -> list[tuple[str, str]]:
    rows = []
    for key, label in LABELS:
        v = machine.get(key)
        if isinstance(v, list):
            v = ", ".join(f"{x:.2f}" for x in v)
        rows.append((label, "unknown" if v is None else str(v)))
    return rows
