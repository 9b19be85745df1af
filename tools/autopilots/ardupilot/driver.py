"""The MAVLink driver that flies ArduCopter SITL as a user's ground station would.

In its own thread, over SITL's MAVLink TCP port (5760 + 10 N, tools/autopilots/ardupilot/sitl.py):
sends a GCS heartbeat, asks for ATTITUDE_TARGET and NAV_CONTROLLER_OUTPUT at 50 Hz and
GLOBAL_POSITION_INT at 10 Hz (sim time), then every 2 s of sim time until airborne: GUIDED
mode, arm, and once armed MAV_CMD_NAV_TAKEOFF to the scenario's take-off altitude. Arming
waits for ArduCopter's own pre-arm checks (GPS, EKF), which take some 20-40 s of sim time
after boot. After the take-off the scenario's setpoints are sent by the physics thread
(tools/autopilots/ardupilot/setpoints.py) through `send_attitude_target`; what the drivers
of both autopilots share (the reports, the locked writes) is tools/autopilots/common/driver.py.
"""

from __future__ import annotations

import math
import select
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.autopilots.ardupilot.sitl import MAVLINK_TCP_BASE, PORT_STRIDE, SitlError
from silbridge.tools.autopilots.common.driver import AutopilotDriver
from silbridge.tools.autopilots.common.log_sink import SOURCE_NAV_CONTROLLER

COPTER_MODE_GUIDED = 4
RETRY_SIM_S = 2.0           # between arming attempts, in sim time (what SITL's checks see)
STREAM_HZ = 50.0
POSITION_STREAM_HZ = 10.0   # GLOBAL_POSITION_INT: the altitude the setpoint forwarder reads


class MavlinkDriver(AutopilotDriver):
    """GCS over SITL's TCP port: GUIDED, arm, take off; reports ArduCopter's target and altitude."""

    def __init__(self, instance: int, *, takeoff_alt_m: float, sim_time_s, on_takeoff, target,
                 connect_timeout_s: float = 30.0, on_takeoff_sent=None, target_feed=None,
                 sim_ns=None):
        super().__init__(f"sitl-mavlink-{instance}", src_system=255, src_component=190,
                         sim_time_s=sim_time_s, target=target, on_takeoff=on_takeoff,
                         on_takeoff_sent=on_takeoff_sent, target_feed=target_feed,
                         sim_ns=sim_ns, connect_timeout_s=connect_timeout_s)
        self.addr = ("127.0.0.1", MAVLINK_TCP_BASE + PORT_STRIDE * instance)
        self.takeoff_alt_m = takeoff_alt_m
        self.mode = None
        self.takeoff_sent = False
        self.rel_alt_m: float | None = None   # GLOBAL_POSITION_INT relative_alt
        self._next_beat = 0.0                 # wall time of the next GCS heartbeat

    # pymavlink "file" interface: the codec writes here (always under _tx_lock)
    def write(self, buf: bytes) -> None:
        if self.sock is not None:
            self.sock.sendall(buf)

    def reported_alt_m(self) -> float | None:
        return self.rel_alt_m

    def _connect(self) -> None:
        end = time.monotonic() + self.connect_timeout_s
        while not self._halt.is_set():
            try:
                self.sock = socket.create_connection(self.addr, timeout=1.0)
                self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                return
            except OSError:
                if time.monotonic() > end:
                    raise SitlError(
                        f"ArduCopter SITL's MAVLink port {self.addr[1]} did not accept a "
                        f"connection in {self.connect_timeout_s:g} s") from None
                time.sleep(0.1)

    def run(self) -> None:
        try:
            self._connect()
            self._loop()
        except Exception as e:  # reported to the flight, which stops the run
            self.error = str(e) or type(e).__name__
        finally:
            if self.sock is not None:
                self.sock.close()

    def _pump(self) -> None:
        """A GCS heartbeat every wall second; what SITL sent within 20 ms, handled."""
        now = time.monotonic()
        if now >= self._next_beat:
            with self._tx_lock:
                self.codec.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._next_beat = now + 1.0
        r, _, _ = select.select([self.sock], [], [], 0.02)
        if r:
            data = self.sock.recv(65536)
            if not data:
                raise SitlError("ArduCopter SITL closed its MAVLink connection")
            for m in self.codec.parse_buffer(data) or []:
                self._handle(m)

    def _loop(self) -> None:
        next_try_sim = None
        streams_asked = False
        while not self._halt.is_set():
            self._pump()
            if self.sysid is None:
                continue
            if not streams_asked:
                for msg_id in (mav.MAVLINK_MSG_ID_ATTITUDE_TARGET,
                               mav.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT):
                    self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / STREAM_HZ)
                self._command(mav.MAV_CMD_SET_MESSAGE_INTERVAL,
                              mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 1e6 / POSITION_STREAM_HZ)
                streams_asked = True
            if self.took_off:
                continue
            t = self.sim_time_s()
            if next_try_sim is not None and t < next_try_sim:
                continue
            next_try_sim = t + RETRY_SIM_S
            if self.mode != COPTER_MODE_GUIDED:
                self._command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                              COPTER_MODE_GUIDED)
            elif not self.armed:
                self._command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            else:
                self.on_takeoff_sent()
                self._command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, 0, 0,
                              self.takeoff_alt_m)
                self.takeoff_sent = True

    def _handle(self, m) -> None:
        kind = m.get_type()
        if kind == "HEARTBEAT":
            if m.autopilot == mav.MAV_AUTOPILOT_INVALID:
                return   # another GCS
            self.sysid = m.get_srcSystem()
            self.armed = bool(m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            self.mode = m.custom_mode
        elif kind == "GLOBAL_POSITION_INT":
            self.rel_alt_m = m.relative_alt * 1e-3
        elif kind == "NAV_CONTROLLER_OUTPUT":
            self.target.set(math.radians(m.nav_roll), math.radians(m.nav_pitch),
                            math.radians(m.nav_bearing), SOURCE_NAV_CONTROLLER)
        else:
            self._report(m, kind)
