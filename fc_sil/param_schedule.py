"""Parameter changes the FC makes at given sim times (a scenario's [[fc_param]] entries).

The bridge owns scenarios and never talks to the FC about parameters, so the glue that
starts a flight (tools/loop/fc_param_events.py) hands the FC this schedule. `FcLoop`
calls `after_batch` after each batch; a change is applied once the FC has finished the
first physics step that ends at or after its time (`loop.last_sim_ns`, set only on a
step's end), so it always lands between the same two steps, however the records of a
run are split into batches: in lockstep the same flight, the same trace.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from silbridge.shm.records import NS_PER_S as _NS


@dataclass(frozen=True)
class ParamEvent:
    at_ns: int          # sim time it is due [ns]
    name: str
    value: float


class ParamSchedule:
    """Pending parameter changes, in time order; each one applied once, then logged."""

    def __init__(self, core, events):
        self.core = core
        self.pending = sorted(events, key=lambda e: e.at_ns)
        self.applied: list[tuple[int, str, float]] = []   # (sim_ns applied, name, value)

    def next_due_ns(self) -> float:
        """When after_batch next acts (fc_loop.py batch_poll)."""
        return self.pending[0].at_ns if self.pending else math.inf

    def after_batch(self, loop) -> None:
        now = loop.last_sim_ns
        while self.pending and now >= self.pending[0].at_ns:
            ev = self.pending.pop(0)
            stored = self.core.set_param(ev.name, ev.value)
            self.applied.append((now, ev.name, stored))
            sink = loop.sink
            if sink is not None:
                sink.event(now, "param", f"{ev.name} = {stored:g} (scenario fc_param, "
                                         f"due at {ev.at_ns / _NS:g} s)",
                           name=ev.name, value=stored, due_ns=ev.at_ns)


def parse_param_at(text: str) -> ParamEvent:
    """'NAME=VALUE@SECONDS' (the `silbridge fc --param-at` form) -> ParamEvent."""
    try:
        assignment, at = text.rsplit("@", 1)
        name, value = assignment.split("=", 1)
        return ParamEvent(at_ns=round(float(at) * _NS), name=name.strip(), value=float(value))
    except ValueError:
        raise ValueError(f"--param-at {text!r}: write NAME=VALUE@SECONDS, "
                         "e.g. SB_ATT_SRC=1@40") from None


def format_param_at(ev: ParamEvent) -> str:
    """The inverse of parse_param_at, exact for the value (repr round-trips a float)."""
    return f"{ev.name}={ev.value!r}@{ev.at_ns / _NS!r}"
