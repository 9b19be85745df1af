"""Requests handed to the vehicle thread and waiting for its answer.

Each call is keyed by (link, sender, command) so a GCS retransmitting a command while the first
copy is still queued gets one answer, not two. A call the vehicle has not started within
``timeout_s`` is withdrawn from the channel and answered TEMPORARILY_REJECTED (the client may
retry); a call that started but never answers is given up after ``hard_timeout_s`` (FAILED).
Runs entirely on the server thread; only the CommandChannel is shared with the vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CommandChannel, VehicleCall

OnReply = Callable[[int, "str | None"], None]


@dataclass(slots=True)
class _Pending:
    key: tuple
    deadline_s: float
    hard_deadline_s: float
    on_reply: OnReply
    cancel_tried: bool = False


class PendingCalls:
    def __init__(self, channel: CommandChannel, timeout_s: float, hard_timeout_s: float):
        self.channel = channel
        self.timeout_s = timeout_s
        self.hard_timeout_s = hard_timeout_s
        self._by_token: dict[int, _Pending] = {}
        self._keys: set[tuple] = set()
        self.timed_out = 0
        self.queue_full = 0

    def busy(self, key: tuple) -> bool:
        return key in self._keys

    def call(self, method: str, args: tuple, key: tuple, on_reply: OnReply, now_s: float) -> None:
        token = self.channel.new_token()
        if not self.channel.submit(VehicleCall(method, args, token)):
            self.queue_full += 1
            on_reply(mav.MAV_RESULT_TEMPORARILY_REJECTED, "Vehicle busy, try again")
            return
        self._by_token[token] = _Pending(key, now_s + self.timeout_s,
                                         now_s + self.hard_timeout_s, on_reply)
        self._keys.add(key)

    def take_replies(self) -> None:
        for token, (result, reason) in self.channel.take_replies():
            p = self._by_token.pop(token, None)
            if p is None:
                continue
            self._keys.discard(p.key)
            p.on_reply(result, reason)

    def check(self, now_s: float) -> float | None:
        """Answer overdue calls; return the next deadline (None when nothing waits)."""
        next_t = None
        for token, p in list(self._by_token.items()):
            if not p.cancel_tried and now_s >= p.deadline_s:
                p.cancel_tried = True
                if self.channel.cancel(token):
                    self._finish(token, mav.MAV_RESULT_TEMPORARILY_REJECTED,
                                 "Vehicle did not take the command in time, retry")
                    continue
            if now_s >= p.hard_deadline_s:
                self._finish(token, mav.MAV_RESULT_FAILED, "Vehicle did not answer")
                continue
            t = p.hard_deadline_s if p.cancel_tried else p.deadline_s
            next_t = t if next_t is None else min(next_t, t)
        return next_t

    def _finish(self, token: int, result: int, reason: str) -> None:
        p = self._by_token.pop(token)
        self._keys.discard(p.key)
        self.timed_out += 1
        p.on_reply(result, reason)
