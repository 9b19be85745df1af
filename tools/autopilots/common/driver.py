"""What the MAVLink drivers of the foreign autopilots share (ArduCopter: ardupilot/driver.py
MavlinkDriver; PX4: px4/driver.py Px4Driver).

A driver is a thread that flies the autopilot as a ground station or companion computer
would: it asks for streams, arms, takes off, and reports what the autopilot says. What each
autopilot wants (its link, its modes, its take-off) stays in its own driver; the reports
they read alike are here: ATTITUDE_TARGET (the autopilot's own attitude target, into
`target` and, stamped, into the run log's /fc/target feed), the ACK that accepts the
take-off, and STATUSTEXT. The physics thread sends attitude targets through
`send_attitude_target` while the driver's thread runs: every write to the link holds
`_tx_lock`, so the two threads never interleave bytes or sequence numbers.
"""

from __future__ import annotations

import threading
from collections import deque

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.bridge.frames import euler_from_quat

from silbridge.tools.autopilots.common.log_sink import SOURCE_ATTITUDE_TARGET


class AutopilotDriver(threading.Thread):
    """A driver thread's shared state and reports; subclasses write(buf) and run()."""

    def __init__(self, name: str, *, src_system: int, src_component: int, sim_time_s,
                 target, on_takeoff, on_takeoff_sent=None, target_feed=None, sim_ns=None,
                 connect_timeout_s: float):
        super().__init__(daemon=True, name=name)
        self.sim_time_s = sim_time_s
        self.target = target
        # Each ATTITUDE_TARGET with the autopilot's stamp and the physics time it was read,
        # for the run log's /fc/target (tools/logs/fc_target.py).
        self.target_feed = target_feed
        self.sim_ns = sim_ns or (lambda: int(self.sim_time_s() * 1e9))
        self.on_takeoff = on_takeoff                 # () on the ACK that accepts the take-off
        self.on_takeoff_sent = on_takeoff_sent or (lambda: None)   # () before each one is sent
        self.connect_timeout_s = connect_timeout_s
        self.codec = mav.MAVLink(self, srcSystem=src_system, srcComponent=src_component)
        self.codec.robust_parsing = True
        self.sock = None
        self.statustext: deque = deque(maxlen=20)
        self.error: str | None = None
        self.sysid: int | None = None
        self.armed = False
        self.took_off = False
        self.setpoints_sent = 0
        self._halt = threading.Event()
        self._tx_lock = threading.Lock()

    def send_attitude_target(self, time_boot_ms: int, q_wxyz, thrust: float,
                             type_mask: int) -> bool:
        """SET_ATTITUDE_TARGET to the vehicle, from any thread. False if the link is not up
        or the autopilot has not been heard yet."""
        if self.sock is None or self.sysid is None or self.error is not None:
            return False
        try:
            with self._tx_lock:
                self.codec.set_attitude_target_send(
                    int(time_boot_ms) & 0xFFFFFFFF, self.sysid, 1, type_mask,
                    [float(v) for v in q_wxyz], 0.0, 0.0, 0.0, float(thrust))
        except OSError as e:   # the run stops on driver.error, as for the driver's own sends
            self.error = f"sending SET_ATTITUDE_TARGET failed: {e.strerror or e}"
            return False
        self.setpoints_sent += 1
        return True

    def stop(self) -> None:
        self._halt.set()
        self.join(3.0)

    def _command(self, command: int, *params) -> None:
        p = list(params) + [0.0] * (7 - len(params))
        with self._tx_lock:
            self.codec.command_long_send(self.sysid or 1, 1, command, 0, *p)

    def _report(self, m, kind: str) -> None:
        """The reports every autopilot sends alike (see the module text)."""
        if kind == "ATTITUDE_TARGET":
            euler = euler_from_quat(*m.q)
            self.target.set(*euler, SOURCE_ATTITUDE_TARGET)
            if self.target_feed is not None:
                self.target_feed.put(self.sim_ns(), m.time_boot_ms * 1_000_000, *euler)
        elif kind == "COMMAND_ACK":
            if m.command == mav.MAV_CMD_NAV_TAKEOFF and m.result == mav.MAV_RESULT_ACCEPTED \
                    and not self.took_off:
                self.took_off = True
                self.on_takeoff()
        elif kind == "STATUSTEXT":
            self.statustext.append(m.text)
