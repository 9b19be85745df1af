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
from silbridge.mavlink.gcs import ftp
from silbridge.mavlink.gcs import setpoints
from silbridge.mavlink.gcs import stream_params
from silbridge.mavlink.endpoints import Endpoint, parse_endpoint, parse_endpoints
from silbridge.mavlink.errors import ParamFileError
from silbridge.mavlink.link import Link, TcpListener, open_endpoint
from silbridge.mavlink.gcs.geo_store import GeoStore
from silbridge.mavlink.gcs.mission_protocol import MissionProtocol
from silbridge.mavlink.gcs.mission_store import MissionStore, home_item
from silbridge.mavlink.gcs.param_protocol import ParamProtocol
from silbridge.mavlink.gcs.pending_calls import PendingCalls
from silbridge.mavlink.gcs.params_file import apply_parm, load_parm, save_store
from silbridge.mavlink.gcs.streams import NOTHING_TO_SEND, STREAMABLE, StreamSchedule
from silbridge.mavlink.gcs.telemetry import ENCODERS, TelemetryContext, statustext_messages
from silbridge.mavlink.gcs.vehicle_api import (CommandChannel, MissionItem, ParamStore, SnapshotBox, VehicleCall,
                          VehicleCommands, VehicleSnapshot)

log = logging.getLogger(__name__)
MSG_ID = {name: getattr(mav, f"MAVLINK_MSG_ID_{name}") for name in (
    "AUTOPILOT_VERSION", "HOME_POSITION", "MISSION_CURRENT")}


@dataclass(slots=True)
class ServerTiming:
    command_timeout_s: float = 0.4        # withdraw a vehicle call not started by then
    command_hard_timeout_s: float = 5.0   # a call started but never answered
    mission_item_resend_s: float = 1.0
    mission_upload_timeout_s: float = 8.0
    param_rate_per_s: float = 2000.0      # PARAM_REQUEST_LIST pacing
    param_save_delay_s: float = 0.5       # coalesce bursts of PARAM_SETs into one file write
    max_sleep_s: float = 0.05


class GcsServer:
    """The autopilot endpoint. Opens every endpoint at construction (a busy port raises
    EndpointError at once); ``start()`` serves on a thread, ``serve_until()`` on the caller's.

    vehicle: VehicleCommands, called only from ``service()`` on the vehicle thread.
    params: ParamStore; ``param_file``: .parm written atomically after PARAM_SETs (and by
    MAV_CMD_PREFLIGHT_STORAGE); load it at start with params_file.load_into_store().
    missions: the MissionStore to serve (a fresh one by default); fence and rally: the
    GeoStores of the plan's other two lists (fresh ones by default).
    """

    def __init__(self, vehicle: VehicleCommands, params: ParamStore,
                 endpoints: Sequence[str | Endpoint] | None = None, sysid: int = 1,
                 compid: int = 1, *, param_file: str | os.PathLike | None = None,
                 missions: MissionStore | None = None, timing: ServerTiming | None = None,
                 fence: GeoStore | None = None, rally: GeoStore | None = None):
        self.vehicle = vehicle
        self.params = params
        self.sysid, self.compid = sysid, compid
        self.param_file = os.fspath(param_file) if param_file is not None else None
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
        self._endpoint_of: dict = {}        # link or listener -> endpoint number (SRn_*)
        self._closed_totals: collections.Counter = collections.Counter()
        now = time.monotonic()
        try:
            for n, ep in enumerate(eps):
                opened = open_endpoint(ep, sysid, compid)
                self._endpoint_of[opened] = n
                if isinstance(opened, TcpListener):
                    self._listeners.append(opened)
                else:
                    self._add_link(opened, now)
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
        self._home_sent: dict[Link, int] = {}
        self._param_dirty_s: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.stats = collections.Counter()
        # mavlink.tlog.TlogWriter or None: both directions of the GCS traffic (--tlog).
        self.tlog = None

    # ============================================================================================
    # API for the vehicle thread and for anyone

    def publish(self, snapshot: VehicleSnapshot) -> None:
        self.snapshots.publish(snapshot)

    def service(self, max_calls: int = 64) -> int:
        """Run queued GCS requests on the calling (vehicle) thread."""
        return self.channel.service(self.vehicle, max_calls)

    def seconds_since_gcs_heartbeat(self) -> float:
        """Since the last HEARTBEAT from system SYSID_MYGCS (inf if never): GCS failsafe input."""
        t = self._gcs_heartbeat_s
        return float("inf") if t is None else time.monotonic() - t

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
                    self._add_link(client, now)
            else:
                for msg in r.receive():
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
    def _add_link(self, link: Link, now: float) -> None:
        self._links.append(link)
        sched = StreamSchedule(now)
        stream_params.apply_stored(self.params, self._endpoint_of.get(link, -1), sched, now)
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

    # -- dispatch -------------------------------------------------------------------------------------
    def _dispatch(self, link: Link, msg, now: float) -> None:
        if msg.get_srcSystem() == self.sysid and msg.get_srcComponent() == self.compid:
            return       # our own traffic looped back
        handler = self._handlers.get(msg.get_type())
        if handler is None:
            return
        try:
            handler(self, link, msg, now)
        except Exception:  # noqa: BLE001 - a bad message must never stop the server
            self.stats["handler_errors"] += 1
            log.exception("error handling %s", msg.get_type())

    def _for_us(self, target_system: int, target_component: int | None = None) -> bool:
        if target_system not in (0, self.sysid):
            return False
        return target_component is None or target_component in (0, self.compid)

    def _my_gcs(self) -> int:
        try:
            return int(self.params.get("SYSID_MYGCS")[0])
        except (KeyError, TypeError, ValueError):
            return 255

    def _on_heartbeat(self, link, msg, now):
        if msg.get_srcSystem() == self._my_gcs():
            self._gcs_heartbeat_s = now

    def _on_param(self, link, msg, now):
        self.param_proto.handle(link, msg)

    def _on_mission(self, link, msg, now):
        self.mission_proto.handle(link, msg, now)

    def _on_command(self, link, msg, now):
        if not self._for_us(msg.target_system, msg.target_component):
            return
        req = cmds.decode(msg)
        self.stats["commands"] += 1
        key = (id(link), req.src_system, req.src_component, req.command)
        if self.pending.busy(key):
            return       # a retransmission of a command still running: one ACK will come
        self._run_plan(link, req, key, self.planner.plan(link, req), now)

    def _on_set_mode(self, link, msg, now):
        if not self._for_us(msg.target_system):
            return
        req = cmds.CommandRequest(mav.MAVLINK_MSG_ID_SET_MODE, float(msg.base_mode),
                                  float(msg.custom_mode), 0, 0, 0, 0, 0, 0, False,
                                  msg.get_srcSystem(), msg.get_srcComponent())
        key = (id(link), req.src_system, req.src_component, req.command)
        if self.pending.busy(key):
            return
        if not msg.base_mode & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            plan = cmds.Immediate(mav.MAV_RESULT_DENIED, "SET_MODE needs CUSTOM_MODE_ENABLED")
        else:
            plan = cmds.Call("set_mode", (int(msg.custom_mode),))
        self._run_plan(link, req, key, plan, now)

    def _on_request_data_stream(self, link, msg, now):
        if not self._for_us(msg.target_system, msg.target_component):
            return
        start = msg.start_stop != 0
        if start and msg.req_message_rate <= 0:
            return          # ArduCopter ignores a start without a rate
        self._schedules[link].request_data_stream(msg.req_stream_id, msg.req_message_rate,
                                                  start, now)
        for name in stream_params.remember(self.params, self._endpoint_of.get(link, -1),
                                           msg.req_stream_id, msg.req_message_rate, start):
            self._param_changed(name)

    def _on_timesync(self, link, msg, now):
        if msg.tc1 == 0:    # a request; answer with our clock in ns, echo theirs
            self.send(link, mav.MAVLink_timesync_message(time.monotonic_ns(), msg.ts1))

    def _on_ftp(self, link, msg, now):
        reply = ftp.reply_message(msg, self.sysid, self.compid)
        if reply is not None:
            self.send(link, reply)

    def _on_position_target(self, link, msg, now):
        if not self._for_us(msg.target_system, msg.target_component):
            return
        if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
            target = setpoints.position_target_local(msg)
        else:
            target = setpoints.position_target_global(msg)
        if target is None:
            self.stats["setpoints_rejected"] += 1
            return
        self._submit_setpoint("set_position_target", (target,))

    def _on_attitude_target(self, link, msg, now):
        if self._for_us(msg.target_system, msg.target_component):
            self._submit_setpoint("set_attitude_target", (setpoints.attitude_target(msg),))

    def _on_manual_control(self, link, msg, now):
        if msg.target in (0, self.sysid) and msg.get_srcSystem() == self._my_gcs():
            self._submit_setpoint("manual_control", (msg.x, msg.y, msg.z, msg.r, msg.buttons))
        else:
            self.stats["setpoints_rejected"] += 1

    def _on_rc_override(self, link, msg, now):
        if self._for_us(msg.target_system, msg.target_component) \
                and msg.get_srcSystem() == self._my_gcs():
            chans = tuple(getattr(msg, f"chan{i}_raw") for i in range(1, 19))
            self._submit_setpoint("rc_override", (chans,))
        else:
            self.stats["setpoints_rejected"] += 1

    _handlers = {
        "HEARTBEAT": _on_heartbeat,
        "PARAM_REQUEST_LIST": _on_param, "PARAM_REQUEST_READ": _on_param, "PARAM_SET": _on_param,
        "MISSION_COUNT": _on_mission, "MISSION_ITEM_INT": _on_mission,
        "MISSION_ITEM": _on_mission, "MISSION_REQUEST_LIST": _on_mission,
        "MISSION_REQUEST_INT": _on_mission, "MISSION_REQUEST": _on_mission,
        "MISSION_CLEAR_ALL": _on_mission, "MISSION_SET_CURRENT": _on_mission,
        "MISSION_ACK": _on_mission,
        "COMMAND_LONG": _on_command, "COMMAND_INT": _on_command,
        "SET_MODE": _on_set_mode,
        "REQUEST_DATA_STREAM": _on_request_data_stream,
        "TIMESYNC": _on_timesync,
        "FILE_TRANSFER_PROTOCOL": _on_ftp,
        "SET_POSITION_TARGET_LOCAL_NED": _on_position_target,
        "SET_POSITION_TARGET_GLOBAL_INT": _on_position_target,
        "SET_ATTITUDE_TARGET": _on_attitude_target,
        "MANUAL_CONTROL": _on_manual_control,
        "RC_CHANNELS_OVERRIDE": _on_rc_override,
    }

    # -- commands and vehicle calls ----------------------------------------------------------------
    def _ack(self, link, req: cmds.CommandRequest, result: int, reason: str | None) -> None:
        if reason:
            sev = (mav.MAV_SEVERITY_INFO if result == mav.MAV_RESULT_ACCEPTED
                   else mav.MAV_SEVERITY_CRITICAL
                   if req.command == mav.MAV_CMD_COMPONENT_ARM_DISARM
                   else mav.MAV_SEVERITY_WARNING)
            self.statustext(sev, reason)
        self.stats["acks"] += 1
        if result == mav.MAV_RESULT_UNSUPPORTED:
            self.stats["commands_unsupported"] += 1
        if not link.closed:
            self.send(link, mav.MAVLink_command_ack_message(
                req.command, result, 0, 0, req.src_system, req.src_component))

    def _run_plan(self, link, req, key, plan, now: float) -> None:
        if isinstance(plan, cmds.Immediate):
            self._ack(link, req, plan.result, plan.reason)
            if plan.after is not None and plan.result == mav.MAV_RESULT_ACCEPTED:
                plan.after()
            return

        def on_reply(result: int, reason: str | None) -> None:
            self._ack(link, req, result, reason)
            if plan.after is not None:
                plan.after(result)

        self.pending.call(plan.method, plan.args, key, on_reply, now)

    def _submit_setpoint(self, method: str, args: tuple) -> None:
        if self.channel.submit(VehicleCall(method, args)):
            self.stats["setpoints"] += 1
        else:
            self.stats["setpoints_dropped"] += 1

    # -- hooks used by CommandPlanner ------------------------------------------------------------
    def request_message(self, link, msg_id: int, req) -> cmds.Immediate:
        # ArduCopter 4.6: ACCEPTED for every message it knows, even with nothing to send yet
        # (HOME_POSITION before home is set: sent when it is), FAILED for an unknown id.
        snap = self.snapshots.latest
        if msg_id not in ENCODERS:
            return cmds.Immediate(mav.MAV_RESULT_FAILED)

        def after() -> None:
            for m in ENCODERS[msg_id](snap, self._telemetry_context()):
                self.send(link, m)
        return cmds.Immediate(mav.MAV_RESULT_ACCEPTED, None, after)

    def set_message_interval(self, link, msg_id: int, interval_us: float) -> cmds.Immediate:
        if msg_id in NOTHING_TO_SEND:
            return cmds.Immediate(mav.MAV_RESULT_ACCEPTED)
        if msg_id not in STREAMABLE:
            return cmds.Immediate(mav.MAV_RESULT_DENIED)
        if interval_us != interval_us:      # NaN
            return cmds.Immediate(mav.MAV_RESULT_DENIED, "Message interval must be a number")
        sched = self._schedules[link]
        now = time.monotonic()
        if interval_us == 0:
            sched.set_default(msg_id, now)
        elif interval_us < 0:
            sched.set_interval(msg_id, None, now)
        else:
            sched.set_interval(msg_id, interval_us * 1e-6, now)
        return cmds.Immediate(mav.MAV_RESULT_ACCEPTED)

    def message_interval(self, link, msg_id: int) -> cmds.Immediate:
        if msg_id not in STREAMABLE:
            return cmds.Immediate(mav.MAV_RESULT_UNSUPPORTED)
        us = self._schedules[link].interval_us(msg_id)
        return cmds.Immediate(mav.MAV_RESULT_ACCEPTED, None, lambda: self.send(
            link, mav.MAVLink_message_interval_message(msg_id, us)))

    def mission_count(self) -> int:
        return self.missions.count()

    def set_current_after(self, link) -> Callable[[int], None]:
        def after(result: int) -> None:
            self._send_mission_current(link)
        return after

    def storage(self, action: int) -> cmds.Immediate:
        if action not in (0, 1):
            return cmds.Immediate(mav.MAV_RESULT_UNSUPPORTED)
        if self.param_file is None:
            return cmds.Immediate(mav.MAV_RESULT_DENIED,
                                  "No parameter file: start with --params FILE")
        try:
            if action == 1:
                self._param_dirty_s = None
                save_store(self.param_file, self.params)
                return cmds.Immediate(mav.MAV_RESULT_ACCEPTED)
            problems = apply_parm(self.params, load_parm(self.param_file))
        except ParamFileError as exc:
            return cmds.Immediate(mav.MAV_RESULT_FAILED, str(exc)[:200])
        for p in problems[:10]:
            self.statustext(mav.MAV_SEVERITY_WARNING, p)
        return cmds.Immediate(mav.MAV_RESULT_ACCEPTED)

    # -- missions ---------------------------------------------------------------------------------
    def _mission_updated(self, items: tuple[MissionItem, ...]) -> None:
        self._submit_setpoint("mission_updated", (items,))

    def _geo_updated(self, mission_type: int, items: tuple[MissionItem, ...]) -> None:
        if mission_type == mav.MAV_MISSION_TYPE_RALLY:
            try:   # ArduCopter keeps the count in RALLY_TOTAL
                self.params.set("RALLY_TOTAL", float(len(items)))
            except KeyError:
                pass
        else:   # ArduCopter 4.6 after every fence upload or clear (debug severity)
            self.statustext(mav.MAV_SEVERITY_DEBUG, "Fence Indexed OK")
        self._submit_setpoint("geo_updated", (mission_type, items))

    def _mission_set_current_msg(self, link, msg, seq: int) -> None:
        if not 0 < seq < self.missions.count():
            self.statustext(mav.MAV_SEVERITY_WARNING, f"Mission has no item {seq}")
            self._send_mission_current(link)
            return
        key = (id(link), msg.get_srcSystem(), msg.get_srcComponent(), "MISSION_SET_CURRENT")
        if self.pending.busy(key):
            return

        def on_reply(result: int, reason: str | None) -> None:
            if reason and result != mav.MAV_RESULT_ACCEPTED:
                self.statustext(mav.MAV_SEVERITY_WARNING, reason)
            self._send_mission_current(link, seq if result == mav.MAV_RESULT_ACCEPTED else None)

        self.pending.call("mission_set_current", (seq,), key, on_reply, time.monotonic())

    def _send_mission_current(self, link, seq: int | None = None) -> None:
        snap = self.snapshots.latest
        msgs = ENCODERS[MSG_ID["MISSION_CURRENT"]](snap, self._telemetry_context())
        if seq is not None:
            msgs[0].seq = seq
        if not link.closed:
            self.send(link, msgs[0])

    def _home_item(self) -> MissionItem | None:
        s = self.snapshots.latest
        if not s.home_set:
            return None
        return home_item(s.home_lat_e7, s.home_lon_e7, s.home_alt_msl_mm / 1000.0)

    # -- parameters -------------------------------------------------------------------------------
    def _param_changed(self, name: str) -> None:
        if self.param_file is not None and self._param_dirty_s is None:
            self._param_dirty_s = time.monotonic()

    def _save_params_now(self) -> None:
        if self._param_dirty_s is None or self.param_file is None:
            return
        self._param_dirty_s = None
        try:
            save_store(self.param_file, self.params)
            self.stats["param_saves"] += 1
        except (ParamFileError, OSError) as exc:
            self.stats["param_save_errors"] += 1
            log.error("parameter save failed: %s", exc)
            if not self._closed:
                self.statustext(mav.MAV_SEVERITY_ERROR, f"Param save failed: {exc}"[:150])

    # -- telemetry ---------------------------------------------------------------------------------
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
