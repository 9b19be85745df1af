"""The GCS server's outbound telemetry: each link's due streams, HOME_POSITION, the outbox.

A mixin of GcsServer (mavlink/gcs/server.py); it runs on the server thread. Each message
due on several links is encoded once from its vehicle snapshot; a snapshot field that
cannot be encoded skips that message (``tx_encode_errors``) rather than the pass. The outbox carries what other threads asked to send (STATUSTEXT,
MISSION_ITEM_REACHED).

Streams run on the vehicle's simulated time (stream_clock.py): a pass runs them over every
snapshot published since the previous pass (snapshot_ring.py), oldest first, so each message
carries the state and time_boot_ms of the instant it was due at, however seldom the server
thread gets to run. The next pass is at the wall time the clock's recent pace brings it to
the next send; one that comes early sends nothing and sleeps again (at least ``MIN_WAIT_S``).
"""

from __future__ import annotations

import logging
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.telemetry import ENCODERS, TelemetryContext

log = logging.getLogger(__name__)
MIN_WAIT_S = 0.0005     # shortest sleep before the next telemetry pass
MSG_ID = {name: getattr(mav, f"MAVLINK_MSG_ID_{name}") for name in (
    "AUTOPILOT_VERSION", "HOME_POSITION", "MISSION_CURRENT")}


class TelemetrySender:
    """GcsServer's telemetry scheduling and sending."""

    def _telemetry_context(self, snap=None) -> TelemetryContext:
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
            errors_comm=bad, unix_us=self._unix_us(snap or self.snapshots.latest))

    def _unix_us(self, snap) -> int:
        """Unix time on the sim clock: the wall's Unix time when the first snapshot was read,
        advanced by sim time from there (ArduCopter SITL's GPS time does the same)."""
        sim_us = snap.time_boot_ms * 1000
        if self._unix_at_sim0_us is None:
            self._unix_at_sim0_us = time.time_ns() // 1000 - sim_us
        return self._unix_at_sim0_us + sim_us

    def _send_telemetry(self, now: float) -> float | None:
        """Run the streams over every snapshot published since the last pass (the latest one
        again if none: the clock may go on without sim time); returns the wall time of the
        next pass, or None while sim time has no known pace (the server's idle period)."""
        wall_us = int(now * 1e6)
        snaps = self._recent.take() or [self.snapshots.latest]
        if self._recent.lost:       # the server thread fell more than the ring behind
            self.stats["tx_snapshots_lost"] = self._recent.lost
        self._announce_home(snaps[-1])
        ctx: TelemetryContext | None = None
        next_t = self._next_due_us()
        for snap in snaps:
            clock_us = self._stream_clock.update(snap.time_boot_ms * 1000, wall_us)
            if next_t is None or clock_us < next_t:
                continue
            if ctx is None:
                ctx = self._telemetry_context(snap)
            ctx.unix_us = self._unix_us(snap)
            self._send_due(snap, ctx)
            next_t = self._next_due_us()
        wait_us = None if next_t is None else self._stream_clock.wall_us_until(next_t)
        return None if wait_us is None else now + max(MIN_WAIT_S, wait_us * 1e-6)

    def _next_due_us(self) -> int | None:
        due = [t for link in self._links if link.can_send
               for t in (self._schedules[link].next_due_us(),) if t is not None]
        return min(due) if due else None

    def _send_due(self, snap, ctx: TelemetryContext) -> None:
        """Every link's messages due at the clock's now, encoded once each from snap."""
        cache: dict[int, list] = {}
        for link in self._links:
            if not link.can_send:
                continue
            for mid in self._schedules[link].due():
                if mid not in cache:
                    try:
                        cache[mid] = ENCODERS[mid](snap, ctx)
                    except Exception:  # noqa: BLE001 - a bad snapshot field: skip message
                        self.stats["tx_encode_errors"] += 1
                        log.exception("cannot build message %d", mid)
                        cache[mid] = []
                for m in cache[mid]:
                    self.send(link, m)

    def _announce_home(self, snap) -> None:
        # ArduCopter announces a new home unasked, once when it is first set and once at
        # arming (MAVSDK's "home ok" waits for it); otherwise on request or stream
        home = snap.home_epoch if snap.home_set else None
        if home is None:
            return
        msgs = None
        for link in self._links:
            if link.can_send and self._home_sent.get(link) != home:
                self._home_sent[link] = home
                if msgs is None:
                    msgs = ENCODERS[MSG_ID["HOME_POSITION"]](snap, self._telemetry_context(snap))
                for m in msgs:
                    self.send(link, m)

    def _drain_outbox(self) -> None:
        while self._outbox:
            item = self._outbox.popleft()
            if item[0] == "statustext":
                self.statustext(item[1], item[2])
            elif item[0] == "reached":
                self.broadcast(mav.MAVLink_mission_item_reached_message(item[1]))
            elif item[0] == "link_lost":    # in order with the STATUSTEXTs (server.py)
                self.pending.take_replies()     # an ACK posted before it goes out first
                self._link_lost = item[1]
