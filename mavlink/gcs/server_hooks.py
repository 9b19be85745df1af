"""What the GCS server's helpers call back: the command planner, the mission and parameter
protocols.

A mixin of GcsServer (mavlink/gcs/server.py). commands.CommandPlanner asks the server for
the answers that need its state (REQUEST_MESSAGE, message intervals, the mission count,
PREFLIGHT_STORAGE); MissionProtocol reports uploads and MISSION_SET_CURRENT; ParamProtocol
reports changed parameters, which (when the server may save: ``save_params``) are written to
the .parm file after a short delay so a burst of PARAM_SETs costs one file write.
"""

from __future__ import annotations

import logging
import time
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.errors import ParamFileError
from silbridge.mavlink.gcs import commands as cmds
from silbridge.mavlink.gcs.mission_store import home_item
from silbridge.mavlink.gcs.params_file import apply_parm, load_parm, save_store
from silbridge.mavlink.gcs.server_telemetry import MSG_ID
from silbridge.mavlink.gcs.streams import NOTHING_TO_SEND, STREAMABLE
from silbridge.mavlink.gcs.telemetry import ENCODERS
from silbridge.mavlink.gcs.vehicle_api import MissionItem

log = logging.getLogger(__name__)


class ServerHooks:
    """GcsServer's answers to its command planner and protocols."""

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
        if interval_us == 0:
            sched.set_default(msg_id)
        elif interval_us < 0:
            sched.set_interval(msg_id, None)
        else:
            sched.set_interval(msg_id, interval_us)
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
        if action == 1 and not self.save_params:
            return cmds.Immediate(mav.MAV_RESULT_DENIED,
                                  "Parameter file is read-only: start with --save-params")
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
        if self.save_params and self._param_dirty_s is None:
            self._param_dirty_s = time.monotonic()

    def _save_params_now(self) -> None:
        if self._param_dirty_s is None or not self.save_params:
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
