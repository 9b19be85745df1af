"""The MAVLink driver that flies PX4 SITL as a companion computer would, on its offboard link.

PX4 instance N's API/offboard link ('onboard' mode) listens on UDP 14580+N and sends to
127.0.0.1:14540+N: the driver binds 14540+N and talks back to 14580+N. In its own thread it
sends a heartbeat (1 Hz wall), asks for ATTITUDE_TARGET and LOCAL_POSITION_NED at STREAM_HZ
(sim time; again every STREAM_RETRY_SIM_S until each has arrived: PX4 sometimes drops the
first request at boot, and without LOCAL_POSITION_NED the companion's altitude loop has no
altitude, the forwarder starts late on its 10 s timer and holds hover thrust open loop),
then every RETRY_SIM_S of sim time until the take-off is accepted: arm (PX4
arms once its pre-flight checks pass, some 10-30 s of sim time after boot; we ask only once
its height at rest has settled, tools/autopilots/px4/rest_height.py, and report
`height_unsettled` when it does not, so the flight can restart PX4), and once armed
MAV_CMD_NAV_TAKEOFF (altitude: MIS_TAKEOFF_ALT, set to the scenario's). After the take-off,
`want_offboard()` (from the setpoint forwarder, once it streams) makes it switch PX4 to
OFFBOARD (MAV_CMD_DO_SET_MODE, custom main mode 6) until the heartbeat says so: PX4 accepts
the switch only while attitude targets arrive (> 2 Hz), which the forwarder guarantees.

Reported: ATTITUDE_TARGET (PX4's attitude controller target) into `target`, the local
altitude and climb rate (LOCAL_POSITION_NED), armed state, PX4's main/sub mode, STATUSTEXT,
and the sim times of the first heartbeat in OFFBOARD and of the first one out of it after
that (`offboard_since_s`, `offboard_left_s`): `offboard` alone is only the mode at the end.
`send_attitude_target` is called from the physics thread; every write holds `_tx_lock`.
"""

from __future__ import annotations

import math
import select
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.autopilots.common.driver import AutopilotDriver
from silbridge.tools.autopilots.px4.rest_height import RestHeightCheck
from silbridge.tools.autopilots.px4.sitl import OFFBOARD_LOCAL_BASE, OFFBOARD_REMOTE_BASE, Px4Error

STREAM_HZ = 50.0
RETRY_SIM_S = 2.0
MODE_RETRY_SIM_S = 0.5
STREAM_RETRY_SIM_S = 0.5
STREAMS = (mav.MAVLINK_MSG_ID_ATTITUDE_TARGET, mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED)
MAIN_MODE_AUTO, MAIN_MODE_OFFBOARD = 4, 6
SUB_MODE_TAKEOFF = 2


class Px4Driver(AutopilotDriver):
    def __init__(self, instance: int, *, sim_time_s, target, on_takeoff, on_takeoff_sent=None,
                 connect_timeout_s: float = 60.0, target_feed=None, sim_ns=None):
        super().__init__(f"px4-mavlink-{instance}", src_system=254, src_component=191,
                         sim_time_s=sim_time_s, target=target, on_takeoff=on_takeoff,
                         on_takeoff_sent=on_takeoff_sent, target_feed=target_feed,
                         sim_ns=sim_ns, connect_timeout_s=connect_timeout_s)
        self.peer = ("127.0.0.1", OFFBOARD_LOCAL_BASE + instance)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind(("127.0.0.1", OFFBOARD_REMOTE_BASE + instance))
        except OSError as e:
            self.sock.close()
            raise Px4Error(f"cannot bind PX4's offboard port {OFFBOARD_REMOTE_BASE + instance} "
                           f"({e.strerror}): another program uses PX4 instance {instance}") from None
        self.main_mode = self.sub_mode = None
        self.offboard_wanted = False
        self.offboard_since_s: float | None = None   # sim time, first heartbeat in OFFBOARD
        self.offboard_left_s: float | None = None    # ... first one out of it after that
        self.heard: set[int] = set()                  # message ids received from PX4
        self.alt_m: float | None = None        # LOCAL_POSITION_NED -z
        self.climb_m_s: float | None = None    # LOCAL_POSITION_NED -vz
        self.rest_height = RestHeightCheck()
        self.height_unsettled: str | None = None   # why, when the check failed (run stops)

    # pymavlink "file" interface (always under _tx_lock)
    def write(self, buf: bytes) -> None:
        self.sock.sendto(buf, self.peer)

    @property
    def offboard(self) -> bool:
        return self.main_mode == MAIN_MODE_OFFBOARD

    def want_offboard(self) -> None:
        self.offboard_wanted = True

    def run(self) -> None:
        try:
            self._loop()
        except Exception as e:  # noqa: BLE001 - reported to the flight, which stops the run
            self.error = str(e) or type(e).__name__
        finally:
            self.sock.close()

    def _loop(self) -> None:
        t0 = time.monotonic()
        next_beat = 0.0
        next_try = next_mode = None
        next_ask = None
        while not self._halt.is_set():
            now = time.monotonic()
            if now >= next_beat:
                with self._tx_lock:
                    self.codec.heartbeat_send(mav.MAV_TYPE_ONBOARD_CONTROLLER,
                                              mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
                next_beat = now + 1.0
            r, _, _ = select.select([self.sock], [], [], 0.02)
            if r:
                data = self.sock.recv(65536)
                for m in self.codec.parse_buffer(data) or []:
                    self._handle(m)
            if self.sysid is None:
                if now - t0 > self.connect_timeout_s:
                    raise Px4Error(f"no heartbeat from PX4 on UDP {self.sock.getsockname()[1]} "
                                   f"in {self.connect_timeout_s:g} s")
                continue
            t = self.sim_time_s()
            missing = [i for i in STREAMS if i not in self.heard]
            if missing and (next_ask is None or t >= next_ask):
                next_ask = t + STREAM_RETRY_SIM_S
                for msg_id in missing:
                    self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / STREAM_HZ)
            if not self.took_off:
                if not self.armed and self.rest_height.failed(t):
                    self.height_unsettled = self.rest_height.why()
                    return
                if next_try is None or t >= next_try:
                    next_try = t + RETRY_SIM_S
                    if not self.armed:
                        if self.rest_height.settled:
                            self._command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
                    else:
                        self.on_takeoff_sent()
                        self._command(mav.MAV_CMD_NAV_TAKEOFF, -1, 0, 0, math.nan, math.nan,
                                      math.nan, math.nan)
            elif self.offboard_wanted and not self.offboard:
                if next_mode is None or t >= next_mode:
                    next_mode = t + MODE_RETRY_SIM_S
                    self._command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                                  MAIN_MODE_OFFBOARD, 0)

    def _note_offboard(self) -> None:
        if self.offboard:
            if self.offboard_since_s is None:
                self.offboard_since_s = self.sim_time_s()
        elif self.offboard_since_s is not None and self.offboard_left_s is None:
            self.offboard_left_s = self.sim_time_s()

    def _handle(self, m) -> None:
        kind = m.get_type()
        self.heard.add(m.get_msgId())
        if kind == "HEARTBEAT":
            if m.autopilot != mav.MAV_AUTOPILOT_PX4:
                return
            self.sysid = m.get_srcSystem()
            self.armed = bool(m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            self.main_mode = (m.custom_mode >> 16) & 0xFF
            self.sub_mode = (m.custom_mode >> 24) & 0xFF
            self._note_offboard()
        elif kind == "LOCAL_POSITION_NED":
            self.alt_m, self.climb_m_s = -m.z, -m.vz
            if not self.armed:
                self.rest_height.feed(self.sim_time_s(), m.z, m.vz)
        else:
            self._report(m, kind)
