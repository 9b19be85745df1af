"""What `silbridge bridge` hands to the `silbridge fc` that attaches to it.

The two programs share only the segment's words, which carry the run's mode and rates but
no parameters; yet `bridge --param/--feature-off/--params` must reach our FC, not be
dropped. The bridge writes them to a small JSON file named after the instance, next to the
other temporary files; `silbridge fc --instance NAME` takes it (reads and removes it) when it
starts, and applies its own command line on top. A file still there when the bridge ends
means no `silbridge fc` took it (a foreign autopilot flew): the bridge says so and removes it.
"""

from __future__ import annotations

import json
import os
import tempfile


def handover_path(instance: str) -> str:
    return os.path.join(tempfile.gettempdir(), f"silbridge-{instance}.fc-handover.json")


def write_handover(instance: str, *, params: dict, features_off: tuple,
                   param_file: str | None) -> str | None:
    """Write the FC's options for `instance`; None (and no file) when there are none."""
    if not (params or features_off or param_file):
        return None
    path = handover_path(instance)
    data = {"bridge_pid": os.getpid(), "params": dict(params),
            "features_off": list(features_off),
            "param_file": os.path.abspath(param_file) if param_file else None}
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w") as fh:
        json.dump(data, fh)
    os.replace(tmp, path)       # the FC never reads half a file
    return path


def take_handover(instance: str) -> dict:
    """The bridge's options for this FC ({} if none), removing the file. A file left by a
    bridge that no longer runs (killed) is stale: removed, not applied."""
    path = handover_path(instance)
    try:
        with open(path) as fh:
            data = json.load(fh)
    except FileNotFoundError:
        return {}
    try:
        os.unlink(path)
    except FileNotFoundError:
        return {}       # another FC took it first
    return data if _alive(int(data.get("bridge_pid", 0))) else {}


def untaken(path: str | None) -> bool:
    """Remove the bridge's file; True if it was still there (no FC took it)."""
    if path is None:
        return False
    try:
        os.unlink(path)
    except FileNotFoundError:
        return False
    return True


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
