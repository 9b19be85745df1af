"""The GCS server's inbound side: one handler per message type, commands turned into ACKs.

A mixin of GcsServer (mavlink/gcs/server.py); it runs on the server thread. A message
from our own system and component (traffic looped back) is ignored, an unknown type is
dropped, and an exception in a handler is logged and counted (``handler_errors``), never
allowed to stop the server. Commands go through commands.CommandPlanner: an Immediate is
ACKed at once, a Call runs on the vehicle thread and is ACKed when the vehicle answers
(pending_calls.PendingCalls). Setpoints are queued to the vehicle without an answer.
"""

from __future__ import annotations

import logging

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs import commands as cmds
from silbridge.mavlink.gcs import ftp
from silbridge.mavlink.gcs import setpoints
from silbridge.mavlink.gcs import stream_params
from silbridge.mavlink.gcs.vehicle_api import VehicleCall
from silbridge.mavlink.link import Link

log = logging.getLogger(__name__)


class MessageDispatch:
    """GcsServer's message handlers (state lives on the server: see GcsServer.__init__)."""

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
            self.gcs_heartbeats += 1

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
                                                  start)
        for name in stream_params.remember(self.params, self._endpoint_of.get(link, -1),
                                           msg.req_stream_id, msg.req_message_rate, start):
            self._param_changed(name)

    def _on_timesync(self, link, msg, now):
        if msg.tc1 == 0:    # a request; answer with our clock in ns, echo theirs
            # our clock is sim time, as ArduCopter SITL answers (its tc1 runs at --speedup)
            now_ns = self.snapshots.latest.time_boot_ms * 1_000_000
            self.send(link, mav.MAVLink_timesync_message(max(1, now_ns), msg.ts1))

    def _on_ftp(self, link, msg, now):
        reply = ftp.reply_message(msg, self.sysid, self.compid)
        if reply is not None:
            self.send(link, reply)

    def _on_position_target(self, link, msg, now):
        if not self._for_us(msg.target_system, msg.target_component):
            return
        # any frame goes on: ArduCopter answers one it cannot fly by stopping (the vehicle's call)
        if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
            target = setpoints.position_target_local(msg)
        else:
            target = setpoints.position_target_global(msg)
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
