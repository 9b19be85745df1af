"""The GCS server's outbound telemetry: each link's due streams, HOME_POSITION, the outbox.

A mixin of GcsServer (mavlink/gcs/server.py); it runs on the server thread. Each message
due on several links is encoded once per pass from the latest vehicle snapshot; a
snapshot field that cannot be encoded skips that message (``tx_encode_errors``) rather
than the pass. The outbox carries what other threads asked to send (STATUSTEXT,
MISSION_ITEM_REACHED).
"""

from __future__ import annotations

import logging

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.telemetry import ENCODERS, TelemetryContext

log = logging.getLogger(__name__)
MSG_ID = {name: getattr(mav, f"MAVLINK_MSG_ID_{name}") for name in (
    "AUTOPILOT_VERSION", "HOME_POSITION", "MISSION_CURRENT")}


class TelemetrySender:
    """GcsServer's telemetry scheduling and sending."""

    def _telemetry_context(self) -> TelemetryContext:
        ok = bad = 0
        for link in self._links:
            ok += link.rx.rx_ok
            bad += link.rx.rx_bad_crc + link.rx.rx_malformed + link.rx.rx_unknown
        try:
            pid_mask = int(self.params.get("GCS_PID_MASK")[0])
        except (KeyError, TypeError, ValueError):
            pid_mask = 0
        return TelemetryContext(
            mission_total=max(0, self.missions.count() - 1), pid_mask=pid_mask,
            drop_rate_comm_cpct=(bad * 10000 // (ok + bad)) if ok + bad else 0,
            errors_comm=bad)

    def _send_telemetry(self, now: float) -> float | None:
        snap = self.snapshots.latest
        ctx: TelemetryContext | None = None
        cache: dict[int, list] = {}
        home = snap.home_epoch if snap.home_set else None
        next_t = None
        for link in self._links:
            sched = self._schedules[link]
            if link.can_send and home is not None and self._home_sent.get(link) != home:
                # ArduCopter announces a new home unasked, once when it is first set and once
                # at arming (MAVSDK's "home ok" waits for it); otherwise on request or stream
                self._home_sent[link] = home
                if ctx is None:
                    ctx = self._telemetry_context()
                for m in ENCODERS[MSG_ID["HOME_POSITION"]](snap, ctx):
                    self.send(link, m)
            if link.can_send:
                for mid in sched.due(now):
                    if mid not in cache:
                        if ctx is None:
                            ctx = self._telemetry_context()
                        try:
                            cache[mid] = ENCODERS[mid](snap, ctx)
                        except Exception:  # noqa: BLE001 - a bad snapshot field: skip message
                            self.stats["tx_encode_errors"] += 1
                            log.exception("cannot build message %d", mid)
                            cache[mid] = []
                    for m in cache[mid]:
                        self.send(link, m)
            t = sched.next_due_s()
            if t is not None and link.can_send:
                next_t = t if next_t is None else min(next_t, t)
        return next_t

    def _drain_outbox(self) -> None:
        while self._outbox:
            item = self._outbox.popleft()
            if item[0] == "statustext":
                self.statustext(item[1], item[2])
            elif item[0] == "reached":
                self.broadcast(mav.MAVLink_mission_item_reached_message(item[1]))
