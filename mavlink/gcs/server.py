"""GcsServer: the autopilot side of MAVLink, on its own thread, for any number of GCS links.

Threading (the control loop must never wait for a GCS):
* the server thread owns every socket and all protocol state; it sleeps in select() until a
  socket is readable, the vehicle posts a reply, or the next telemetry/param/mission deadline;
* the vehicle thread calls ``publish(snapshot)`` (one reference swap) and ``service()`` (runs
  queued GCS requests, posts replies, wakes the server through a pipe) at its outer-loop rate;
* ``send_statustext`` and ``mission_item_reached`` may be called from any thread.

Commands queued for the vehicle are ACKed when the vehicle answers. One that has not started
within ``command_timeout_s`` (0.4 s, inside the 0.5 s clients allow) is withdrawn and answered
TEMPORARILY_REJECTED, so a stalled vehicle never leaves a GCS without an answer.

Bad input of any kind is counted (``counters()``) and dropped; an exception in a handler is
logged and counted, never allowed to stop the server.

This file holds the server's state, its threads, sockets and output; its other sides are
mixins: the message handlers (server_dispatch.py), the answers to the command planner and
the protocols (server_hooks.py), and the telemetry streams (server_telemetry.py).
"""

from __future__ import annotations

import collections
import logging
import os
import select
import struct
import threading
import time
from dataclasses import dataclass
from typing import Callable, Sequence

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs import commands as cmds
from silbridge.mavlink.gcs import stream_params
from silbridge.mavlink.endpoints import Endpoint, parse_endpoint, parse_endpoints
from silbridge.mavlink.link import Link, TcpListener, open_endpoint
from silbridge.mavlink.gcs.geo_store import GeoStore
from silbridge.mavlink.gcs.mission_protocol import MissionProtocol
from silbridge.mavlink.gcs.mission_store import MissionStore
from silbridge.mavlink.gcs.param_protocol import ParamProtocol
from silbridge.mavlink.gcs.pending_calls import PendingCalls
from silbridge.mavlink.gcs.server_dispatch import MessageDispatch
from silbridge.mavlink.gcs.server_hooks import ServerHooks
from silbridge.mavlink.gcs.server_telemetry import MSG_ID, TelemetrySender
from silbridge.mavlink.gcs.snapshot_ring import SnapshotRing
from silbridge.mavlink.gcs.stream_clock import StreamClock
from silbridge.mavlink.gcs.streams import StreamSchedule
from silbridge.mavlink.gcs.telemetry import statustext_messages
from silbridge.mavlink.gcs.vehicle_api import (CommandChannel, ParamStore, SnapshotBox,
                                               VehicleCommands, VehicleSnapshot)

log = logging.getLogger(__name__)
__all__ = ["GcsServer", "ServerTiming", "MSG_ID"]


@dataclass(slots=True)
class ServerTiming:
    command_timeout_s: float = 0.4        # withdraw a vehicle call not started by then
    command_hard_timeout_s: float = 5.0   # a call started but never answered
    mission_item_resend_s: float = 1.0
    mission_upload_timeout_s: float = 8.0
    param_rate_per_s: float = 2000.0      # PARAM_REQUEST_LIST pacing
    param_save_delay_s: float = 0.5       # coalesce bursts of PARAM_SETs into one file write
    max_sleep_s: float = 0.05


class GcsServer(MessageDispatch, ServerHooks, TelemetrySender):
    """The autopilot endpoint. Opens every endpoint at construction (a busy port raises
    EndpointError at once); ``start()`` serves on a thread, ``serve_until()`` on the caller's.

    vehicle: VehicleCommands, called only from ``service()`` on the vehicle thread.
    params: ParamStore; ``param_file``: the vehicle's .parm; MAV_CMD_PREFLIGHT_STORAGE reads it
    back, and with ``save_params`` it is written atomically after PARAM_SETs (and by
    PREFLIGHT_STORAGE's write). Without ``save_params`` the file is never written (`silbridge
    --params FILE` is read-only unless --save-params). Load it at start with
    params_file.load_into_store().
    missions: the MissionStore to serve (a fresh one by default); fence and rally: the
    GeoStores of the plan's other two lists (fresh ones by default).
    """

    def __init__(self, vehicle: VehicleCommands, params: ParamStore,
                 endpoints: Sequence[str | Endpoint] | None = None, sysid: int = 1,
                 compid: int = 1, *, param_file: str | os.PathLike | None = None,
                 save_params: bool = True,
                 missions: MissionStore | None = None, timing: ServerTiming | None = None,
                 fence: GeoStore | None = None, rally: GeoStore | None = None):
        self.vehicle = vehicle
        self.params = params
        self.sysid, self.compid = sysid, compid
        self.param_file = os.fspath(param_file) if param_file is not None else None
        self.save_params = save_params and self.param_file is not None
        self.timing = timing or ServerTiming()
        self.missions = missions or MissionStore()
        self.fence = fence or GeoStore(mav.MAV_MISSION_TYPE_FENCE)
        self.rally = rally or GeoStore(mav.MAV_MISSION_TYPE_RALLY)
        self.snapshots = SnapshotBox()
        eps = [e if isinstance(e, Endpoint) else parse_endpoint(e) for e in endpoints] \
            if endpoints else parse_endpoints(None)

        self._closed = False
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self.channel = CommandChannel(wake=self._wake)
        self._links: list[Link] = []
        self._listeners: list[TcpListener] = []
        self._schedules: dict[Link, StreamSchedule] = {}
        self._stream_clock = StreamClock()      # sim time: every link's streams run on it
        self._recent = SnapshotRing()           # every snapshot, for the streams
        self._unix_at_sim0_us: int | None = None
        self._endpoint_of: dict = {}        # link or listener -> endpoint number (SRn_*)
        self._closed_totals: collections.Counter = collections.Counter()
        try:
            for n, ep in enumerate(eps):
                opened = open_endpoint(ep, sysid, compid)
                self._endpoint_of[opened] = n
                if isinstance(opened, TcpListener):
                    self._listeners.append(opened)
                else:
                    self._add_link(opened)
        except Exception:
            self._close_sockets()
            raise

        self.param_proto = ParamProtocol(params, self, sysid, compid,
                                         rate_per_s=self.timing.param_rate_per_s,
                                         on_change=self._param_changed)
        self.mission_proto = MissionProtocol(
            self.missions, self, sysid, compid, on_updated=self._mission_updated,
            on_set_current=self._mission_set_current_msg, home_item=self._home_item,
            item_resend_s=self.timing.mission_item_resend_s,
            upload_timeout_s=self.timing.mission_upload_timeout_s,
            geo_stores={mav.MAV_MISSION_TYPE_FENCE: self.fence,
                        mav.MAV_MISSION_TYPE_RALLY: self.rally},
            on_geo_updated=self._geo_updated)
        self.planner = cmds.CommandPlanner(self)
        self.pending = PendingCalls(self.channel, self.timing.command_timeout_s,
                                    self.timing.command_hard_timeout_s)
        self._outbox: collections.deque = collections.deque()
        self._statustext_id = 0
        self._gcs_heartbeat_s: float | None = None
        self.gcs_heartbeats = 0     # HEARTBEATs heard from SYSID_MYGCS (the FC times them on sim time)
        self._home_sent: dict[Link, int] = {}
        self._param_dirty_s: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.stats = collections.Counter()
        # mavlink.tlog.TlogWriter or None: both directions of the GCS traffic (--tlog).
        self.tlog = None
        # An injected GCS link loss (fc_sil/fault_inject.py): nothing heard, nothing sent.
        self._link_lost = False

    # ============================================================================================
    # API for the vehicle thread and for anyone

    def publish(self, snapshot: VehicleSnapshot) -> None:
        self.snapshots.publish(snapshot)
        self._recent.put(snapshot)

    def service(self, max_calls: int = 64) -> int:
        """Run queued GCS requests on the calling (vehicle) thread."""
        return self.channel.service(self.vehicle, max_calls)

    def seconds_since_gcs_heartbeat(self) -> float:
        """Since the last HEARTBEAT from system SYSID_MYGCS (inf if never): GCS failsafe input."""
        t = self._gcs_heartbeat_s
        return float("inf") if t is None else time.monotonic() - t

    def set_link_lost(self, lost: bool) -> None:
        """An injected loss of the GCS link (vehicle thread): queued in order with the
        STATUSTEXTs, after the command replies already posted (the injecting command's ACK),
        every message in is dropped unread and nothing goes out, until set_link_lost(False);
        what is queued after that goes out."""
        self._outbox.append(("link_lost", bool(lost)))
        self._wake()

    @property
    def link_lost(self) -> bool:
        return self._link_lost

    def send_statustext(self, severity: int, text: str) -> None:
        self._outbox.append(("statustext", int(severity), str(text)))
        self._wake()

    def mission_item_reached(self, seq: int) -> None:
        self._outbox.append(("reached", int(seq)))
        self._wake()

    def local_addresses(self) -> dict[str, tuple[str, int]]:
        """Bound address of every endpoint (tests use port 0 and read the real port here)."""
        out = {lst.name: lst.local_address for lst in self._listeners}
        for link in list(self._links):
            if hasattr(link, "local_address"):
                out[link.name] = link.local_address
        return out

    def counters(self) -> dict:
        """Totals over every link (closed ones included) plus server-level statistics."""
        for _ in range(5):
            try:
                return self._counters()
            except RuntimeError:      # a dict resized by the server thread while copying
                continue
        return self._counters()

    def _counters(self) -> dict:
        total = collections.Counter(self._closed_totals)
        tx_by_id: collections.Counter = collections.Counter()
        rx_by_id: collections.Counter = collections.Counter()
        for link in list(self._links):
            c = link.counters()
            tx_by_id.update(c.pop("tx_by_id"))
            rx_by_id.update(c.pop("rx_by_id"))
            total.update(c)
        out = dict(total)
        for k in ("rx_packets", "rx_bytes", "rx_ok", "rx_bad_crc", "rx_malformed", "rx_unknown",
                  "tx_msgs", "tx_bytes", "tx_dropped", "tx_errors"):
            out.setdefault(k, 0)
        out["tx_by_id"] = dict(tx_by_id)
        out["rx_by_id"] = dict(rx_by_id)
        out.update(self.stats)
        out["param_sets_ok"] = self.param_proto.sets_ok
        out["param_sets_refused"] = self.param_proto.sets_refused
        out["mission_uploads_ok"] = self.mission_proto.uploads_ok
        out["mission_uploads_failed"] = self.mission_proto.uploads_failed
        out["commands_timed_out"] = self.pending.timed_out
        out["vehicle_queue_full"] = self.pending.queue_full
        out["links"] = len(self._links)
        return out

    # ============================================================================================
    # running

    def start(self) -> "GcsServer":
        if self._thread is None:
            self._thread = threading.Thread(target=self.serve_until, name="gcs-server",
                                            daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread (if any), write pending parameter changes, close the sockets."""
        self._stop.set()
        self._wake()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        self._thread = None
        self._save_params_now()
        self._close_sockets()
        if self.tlog is not None:
            self.tlog.close()

    def serve_until(self, stop: Callable[[], bool] | None = None,
                    timeout_s: float | None = None) -> None:
        """Serve on the calling thread until stop() is true, timeout_s passes, or stop()."""
        end = None if timeout_s is None else time.monotonic() + timeout_s
        while not self._stop.is_set() and not self._closed:
            if stop is not None and stop():
                return
            now = time.monotonic()
            if end is not None and now >= end:
                return
            wait = self._housekeeping(now)
            if end is not None:
                wait = min(wait, max(0.0, end - now))
            self._poll(wait)

    # ============================================================================================
    # the loop

    def _poll(self, wait_s: float) -> None:
        rlist: list = [self._wake_r, *self._links, *self._listeners]
        wlist = [l for l in self._links if l.wants_write()]
        try:
            readable, writable, _ = select.select(rlist, wlist, [], wait_s)
        except (OSError, ValueError):
            # a socket closed under us (TCP peer gone): drop closed links and go on
            self._reap_links()
            return
        now = time.monotonic()
        for r in readable:
            if r is self._wake_r:
                try:
                    while os.read(self._wake_r, 4096):
                        pass
                except (BlockingIOError, InterruptedError):
                    pass
            elif isinstance(r, TcpListener):
                client = r.accept()
                if client is not None:
                    self._endpoint_of[client] = self._endpoint_of.get(r, -1)
                    self._add_link(client)
            else:
                for msg in r.receive():
                    if self._link_lost:
                        self.stats["rx_link_lost"] += 1
                        continue
                    if self.tlog is not None:
                        self.tlog.message(msg)
                    self._dispatch(r, msg, now)
        for w in writable:
            w.flush()
        self._reap_links()

    def _housekeeping(self, now: float) -> float:
        """Everything time-driven; returns how long the loop may sleep."""
        self.pending.take_replies()
        self._drain_outbox()
        next_t = now + self.timing.max_sleep_s
        t = self.pending.check(now)
        if t is not None:
            next_t = min(next_t, t)
        t = self.mission_proto.poll(now)
        if t is not None:
            next_t = min(next_t, t)
        t = self.param_proto.pump(now)
        if t is not None:
            next_t = min(next_t, t)
        t = self._send_telemetry(now)
        if t is not None:
            next_t = min(next_t, t)
        if self._param_dirty_s is not None:
            if now - self._param_dirty_s >= self.timing.param_save_delay_s:
                self._save_params_now()
            else:
                next_t = min(next_t, self._param_dirty_s + self.timing.param_save_delay_s)
        return max(0.0, next_t - time.monotonic())

    # -- links ---------------------------------------------------------------------------------------
    def _add_link(self, link: Link) -> None:
        self._links.append(link)
        sched = StreamSchedule(self._stream_clock)
        stream_params.apply_stored(self.params, self._endpoint_of.get(link, -1), sched)
        self._schedules[link] = sched

    def _reap_links(self) -> None:
        for link in [l for l in self._links if l.closed]:
            c = link.counters()
            c.pop("tx_by_id")
            c.pop("rx_by_id")
            self._closed_totals.update(c)
            self._links.remove(link)
            self._schedules.pop(link, None)
            self._home_sent.pop(link, None)
            self._endpoint_of.pop(link, None)

    def _close_sockets(self) -> None:
        if self._closed:
            return
        self._closed = True
        for link in self._links:
            link.close()
        for lst in self._listeners:
            lst.close()
        for fd in (self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass

    def _wake(self) -> None:
        if self._closed:
            return   # the descriptor number may already belong to another file
        try:
            os.write(self._wake_w, b"\0")
        except (BlockingIOError, OSError):
            pass     # pipe full (a wake-up is already pending) or closed

    # -- output side used by the protocol handlers ----------------------------------------------------
    def send(self, link: Link, msg, *, to_tlog: bool = True) -> None:
        if self._link_lost:
            self.stats["tx_link_lost"] += 1
            return
        try:
            link.send(msg)
        except (struct.error, ValueError, TypeError, OverflowError):
            self.stats["tx_encode_errors"] += 1
            log.exception("cannot encode %s", msg.get_type())
            return
        if to_tlog and self.tlog is not None:
            self.tlog.message(msg)

    def broadcast(self, msg) -> None:
        logged = False      # one tlog record for the frame, whatever the number of links
        for link in self._links:
            if link.can_send:
                self.send(link, msg, to_tlog=not logged)
                logged = True

    def statustext(self, severity: int, text: str) -> None:
        self._statustext_id = self._statustext_id % 255 + 1
        for m in statustext_messages(severity, text, self._statustext_id):
            self.broadcast(m)
