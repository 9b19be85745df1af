"""The simulator's notices to the FC's ground stations: a real-time rate shortfall.

The bridge measures the rates (bridge/rate_watch.py) but has no MAVLink: the FC's vehicle
holds the ground-station links and, with two processes, the run's log. The segment's eight
words are all taken, so the bridge (tools/loop, which may import both sides) writes its
latest notice to a small JSON file named after the instance, replaced atomically; the FC
process reads it when idle, at most twice a wall second, and hands it to `deliver`. In one
process the bridge calls `deliver` directly.

File: {"bridge_pid", "seq": reports so far, "text": the latest STATUSTEXT or null,
"fields": its figures, "final": true once the run's end figures are in}.
"""

from __future__ import annotations

import json
import os
import tempfile
import time

MAV_SEVERITY_WARNING = 4     # MAVLink common.xml: what ArduPilot uses for "SIM:" and EKF notes


def notice_path(instance: str) -> str:
    return os.path.join(tempfile.gettempdir(), f"silbridge-{instance}.sim-notice.json")


class NoticeWriter:
    """Bridge side: one per run; clears a stale file from an earlier run at start."""

    def __init__(self, instance: str):
        self.path = notice_path(instance)
        self.seq = 0
        self.text: str | None = None
        self.remove()

    def __call__(self, text: str | None, fields: dict) -> None:
        """run_bridge's notify: a report (text) or the end figures (text None)."""
        if text is not None:
            self.seq += 1
            self.text = text
        data = {"bridge_pid": os.getpid(), "seq": self.seq, "text": self.text,
                "fields": fields, "final": text is None}
        tmp = f"{self.path}.{os.getpid()}.tmp"
        with open(tmp, "w") as fh:
            json.dump(data, fh)
        os.replace(tmp, self.path)      # the FC never reads half a file

    def remove(self) -> None:
        try:
            os.unlink(self.path)
        except FileNotFoundError:
            pass


class NoticeReader:
    """FC side: poll() when idle; delivers each new report once, and the end figures."""

    def __init__(self, instance: str, loop, every_s: float = 0.5):
        self.path = notice_path(instance)
        self.loop = loop
        self.every_s = every_s
        self.seen_seq = 0
        self.final: dict | None = None
        self._next = 0.0
        self._stamp = None

    def poll(self, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now < self._next:
            return
        self._next = now + self.every_s
        try:
            st = os.stat(self.path)
        except FileNotFoundError:
            return
        stamp = (st.st_mtime_ns, st.st_size)
        if stamp == self._stamp:
            return
        self._stamp = stamp
        try:
            with open(self.path) as fh:
                data = json.load(fh)
        except (OSError, ValueError):
            return      # replaced meanwhile: the next poll reads the new one
        if data.get("seq", 0) > self.seen_seq and data.get("text"):
            self.seen_seq = data["seq"]
            deliver(self.loop, data["text"], data.get("fields", {}))
        if data.get("final") and self.final is None:
            self.final = data.get("fields", {})
            deliver(self.loop, None, self.final)


def deliver(loop, text: str | None, fields: dict, *, log: bool = True) -> None:
    """Give a notice to an FcLoop: the STATUSTEXT to its vehicle (when MAVLink is on; the
    vehicle logs it too) and, with log, the figures to its log's events ("rates")."""
    sup = getattr(loop, "supervisor", None)
    if text is not None and hasattr(sup, "statustext"):
        sup.statustext(MAV_SEVERITY_WARNING, text)
    sink = getattr(loop, "sink", None)
    if log and sink is not None and hasattr(sink, "event"):
        sim_ns = int(getattr(sup, "sim_ns", 0) or 0)
        sink.event(sim_ns, "rates", text or "rates at the end of the run", **fields)
