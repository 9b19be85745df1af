"""The /events channel of a run log: one foxglove.Log-shaped JSON message per event.

Foxglove's Log panel lists these (mode changes, parameter changes, disturbances,
check results); `sim_ns` and `fields` are ours. tools/logs/mcap_log.py's
LogWriter.event() writes them.
"""

from __future__ import annotations

import json

from silbridge.tools.logs.log_format import EVENTS_CHANNEL, to_json
from silbridge.shm.records import NS_PER_S

# foxglove.Log, with our own fields added; Foxglove's Log panel reads the first five.
EVENT_SCHEMA = {
    "title": "foxglove.Log",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "properties": {
            "sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "level": {"type": "integer", "description": "2 = INFO"},
        "name": {"type": "string", "description": "event kind: mode, param, disturbance, check"},
        "message": {"type": "string"},
        "file": {"type": "string"},
        "line": {"type": "integer"},
        "sim_ns": {"type": "integer"},
        "fields": {"type": "object"},
    },
}


class EventChannel:
    """The /events channel of one log, registered on its first event."""

    __slots__ = ("_mcap", "_channel", "count")

    def __init__(self, mcap):
        self._mcap = mcap
        self._channel: int | None = None
        self.count = 0      # events written (the end summary's "events")

    def write(self, sim_ns: int, kind: str, text: str, fields: dict) -> None:
        if self._channel is None:
            schema = self._mcap.register_schema("foxglove.Log", "jsonschema",
                                                json.dumps(EVENT_SCHEMA).encode())
            self._channel = self._mcap.register_channel(EVENTS_CHANNEL, "json", schema)
        sim_ns = int(sim_ns)
        body = {"timestamp": {"sec": sim_ns // NS_PER_S, "nsec": sim_ns % NS_PER_S},
                "level": 2, "name": str(kind), "message": str(text), "file": "", "line": 0,
                "sim_ns": sim_ns, "fields": fields}
        self._mcap.add_message(self._channel, max(sim_ns, 0), max(sim_ns, 0),
                               self.count, [to_json(body).encode()])
        self.count += 1
