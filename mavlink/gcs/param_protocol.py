"""The PARAM_* protocol, ArduPilot style, on top of a vehicle ParamStore.

* PARAM_REQUEST_LIST: every PARAM_VALUE with its stable index and the total count, paced
  (``rate_per_s``) so a Python GCS reading a UDP socket is not flooded; a second request from
  the same link restarts the stream.
* PARAM_REQUEST_READ: by name (index -1) or by index.
* PARAM_SET: the value is checked (finite, fits the integer type) and handed to the store,
  which validates range and applies it to the running loop. Success: PARAM_VALUE with the
  stored value to every link (so every GCS's cache follows). Refusal: value kept, STATUSTEXT
  with the reason, PARAM_VALUE with the current value and PARAM_ERROR to the sender.

``tx`` is the server's output side: send(link, msg), broadcast(msg), statustext(sev, text).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.param_types import coerce, wire_value
from silbridge.mavlink.gcs.vehicle_api import ParamStore


@dataclass(slots=True)
class _ListStream:
    next_index: int
    next_due_s: float


class ParamProtocol:
    def __init__(self, store: ParamStore, tx, sysid: int, compid: int,
                 rate_per_s: float = 2000.0, on_change: Callable[[str], None] | None = None):
        self.store = store
        self.tx = tx
        self.sysid = sysid
        self.compid = compid
        self.names = list(store.names())
        self.index = {n: i for i, n in enumerate(self.names)}
        self.period_s = 1.0 / rate_per_s
        self.on_change = on_change
        self._streams: dict[object, _ListStream] = {}
        self.sets_ok = 0
        self.sets_refused = 0

    # -- encoding ---------------------------------------------------------------------------------
    def value_msg(self, name: str) -> mav.MAVLink_param_value_message:
        value, ptype = self.store.get(name)
        return mav.MAVLink_param_value_message(
            name.encode("ascii"), wire_value(value), ptype, len(self.names), self.index[name])

    def _error(self, link, msg, name: str, index: int, code: int) -> None:
        self.tx.send(link, mav.MAVLink_param_error_message(
            msg.get_srcSystem(), msg.get_srcComponent(),
            name.encode("ascii", "replace")[:16], index, code))

    def _for_us(self, msg) -> bool:
        return (msg.target_system in (0, self.sysid)
                and msg.target_component in (0, self.compid, mav.MAV_COMP_ID_ALL))

    # -- handlers -----------------------------------------------------------------------------------
    def handle(self, link, msg) -> None:
        t = msg.get_type()
        if not self._for_us(msg):
            return
        if t == "PARAM_REQUEST_LIST":
            self._streams[link] = _ListStream(0, time.monotonic())
        elif t == "PARAM_REQUEST_READ":
            self._read(link, msg)
        elif t == "PARAM_SET":
            self._set(link, msg)

    def _read(self, link, msg) -> None:
        if msg.param_index >= 0:
            if msg.param_index >= len(self.names):
                self._error(link, msg, msg.param_id, msg.param_index,
                            mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)
                return
            name = self.names[msg.param_index]
        else:
            name = msg.param_id
            if name not in self.index:
                self._error(link, msg, name, -1, mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)
                return
        self.tx.send(link, self.value_msg(name))

    def _set(self, link, msg) -> None:
        name = msg.param_id
        if name not in self.index:
            self.sets_refused += 1
            self.tx.statustext(mav.MAV_SEVERITY_WARNING, f"Param {name}: unknown parameter")
            self._error(link, msg, name, -1, mav.MAV_PARAM_ERROR_DOES_NOT_EXIST)
            return
        _, ptype = self.store.get(name)
        value, reason = coerce(msg.param_value, ptype)
        if reason is None:
            try:
                reason = self.store.set(name, value)
            except (ValueError, TypeError) as exc:
                reason = str(exc) or type(exc).__name__
        if reason:
            self.sets_refused += 1
            self.tx.statustext(mav.MAV_SEVERITY_WARNING, f"Param {name}: {reason}")
            self.tx.send(link, self.value_msg(name))
            self._error(link, msg, name, self.index[name], mav.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE)
            return
        self.sets_ok += 1
        self.tx.broadcast(self.value_msg(name))
        if self.on_change is not None:
            self.on_change(name)

    # -- paced list streaming --------------------------------------------------------------------
    def pump(self, now_s: float) -> float | None:
        """Send what is due; return the time of the next send, or None when idle."""
        next_due: float | None = None
        for link, st in list(self._streams.items()):
            if getattr(link, "closed", False):
                del self._streams[link]
                continue
            # after a stall, catch up by at most a small burst rather than everything at once
            st.next_due_s = max(st.next_due_s, now_s - 32 * self.period_s)
            while st.next_due_s <= now_s and st.next_index < len(self.names):
                self.tx.send(link, self.value_msg(self.names[st.next_index]))
                st.next_index += 1
                st.next_due_s += self.period_s
            if st.next_index >= len(self.names):
                del self._streams[link]
                continue
            next_due = st.next_due_s if next_due is None else min(next_due, st.next_due_s)
        return next_due

    def streaming(self) -> bool:
        return bool(self._streams)
