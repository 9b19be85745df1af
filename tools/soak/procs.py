"""What the kernel says about the run's processes: RSS and open file descriptors (/proc)."""

from __future__ import annotations

import os


def children(pid: int) -> list[int]:
    """Direct children of pid (from /proc/PID/task/*/children, all threads)."""
    out = []
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for t in tasks:
        try:
            with open(f"/proc/{pid}/task/{t}/children") as f:
                out.extend(int(x) for x in f.read().split())
        except OSError:
            continue
    return out


def tree(pid: int) -> list[int]:
    """pid and all its descendants."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo.extend(children(p))
    return out


def rss_kb(pid: int) -> int | None:
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def fd_count(pid: int) -> int | None:
    try:
        return len(os.listdir(f"/proc/{pid}/fd"))
    except OSError:
        return None


def comm(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            args = f.read().split(b"\0")
    except OSError:
        return "?"
    return " ".join(a.decode(errors="replace") for a in args if a)


def sample(root: int, names: dict[int, str]) -> dict:
    """{name: {"pid", "rss_kb", "fds"}} for root and its descendants. names keeps the label
    given to each pid the first time it is seen ("bridge" for the root, "fc" for its first
    child, then "child2", ...), so a process that restarts shows up as a new name."""
    out = {}
    for pid in tree(root):
        if pid not in names:
            names[pid] = "bridge" if pid == root else ("fc" if len(names) == 1
                                                       else f"child{len(names)}")
        r, n = rss_kb(pid), fd_count(pid)
        if r is not None and n is not None:
            out[names[pid]] = {"pid": pid, "rss_kb": r, "fds": n}
    return out
