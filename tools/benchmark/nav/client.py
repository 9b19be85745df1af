"""The benchmark's MAVLink client: a ground station / companion computer paced on the
vehicle's clock.

Every wait is in sim seconds (`clock()`: the physics time for the autopilots whose physics
runs in this process, the vehicle's time_boot_ms for ours, whose telemetry is stamped on
its sim clock), so a flight reads the same at any --speed. A wall-clock guard only catches
a vehicle that stopped talking. Commands the vehicle refuses raise `Unsupported`; targets it
never reaches raise `Failed`: the run is then reported as such, never crashes the suite.
What differs between autopilots (modes, take-off, how a goto is sent) is in ways.py; this is
the MAVLink they share.
"""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.benchmark.nav.geo import latlon_e7_to_ne, ne_to_latlon_e7

SILENT_WALL_S = 30.0                # no message for this long (wall): the vehicle is gone
HEARTBEAT_WALL_S = 0.5
POSITION_HZ = 20.0                  # GLOBAL_POSITION_INT rate asked for
# SET_POSITION_TARGET_* type_mask bits (POSITION_TARGET_TYPEMASK): ignore what is not sent.
MASK_POSITION_ONLY = 0x0DF8         # velocity, acceleration, yaw, yaw rate ignored
MASK_VELOCITY_YAW = 0x09C7          # position, acceleration, yaw rate ignored


class Unsupported(Exception):
    """The vehicle refused a command the plan needs."""


class Failed(Exception):
    """The vehicle accepted the plan but did not fly it within its budget."""


class TimedOut(Failed):
    """A wait's sim-time budget passed (a retry may follow); the other Failed ends the
    flight at once: the vehicle went silent or the run was interrupted."""


class NavClient:
    def __init__(self, link, home_lat_deg: float, home_lon_deg: float, clock=None,
                 stop=None):
        self.link = link
        self.stop = stop                    # an object whose .requested ends the flight
        self.home = (home_lat_deg, home_lon_deg)
        self.codec = mav.MAVLink(self, srcSystem=255, srcComponent=190)
        self.codec.robust_parsing = True
        self._clock = clock
        self.vehicle_ms = 0                 # the latest time_boot_ms heard
        self.sysid = None
        self.mode = None                    # HEARTBEAT custom_mode, as the autopilot sent it
        self.armed = False
        self.pos_ne = (math.nan, math.nan)  # reported position [m], for sequencing only
        self.rel_alt_m = math.nan
        self.vel_ne = (math.nan, math.nan)
        self.acks: dict[int, int] = {}      # command -> last result
        self.reached: set[int] = set()      # MISSION_ITEM_REACHED seq
        self.texts: list[str] = []
        self._inbox: list = []
        self._next_hb = 0.0
        self._heard_wall = time.monotonic()

    # pymavlink's codec writes here
    def write(self, buf: bytes) -> None:
        self.link.send(buf)

    def clock(self) -> float:
        """Sim seconds: the harness's physics clock, else the vehicle's time_boot_ms."""
        return self._clock() if self._clock is not None else self.vehicle_ms * 1e-3

    # ---- the pump --------------------------------------------------------------------------
    def pump(self, wall_s: float = 0.02) -> None:
        if self.stop is not None and self.stop.requested:
            raise Failed("interrupted")
        now = time.monotonic()
        if now >= self._next_hb:
            self.codec.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._next_hb = now + HEARTBEAT_WALL_S
        data = self.link.recv(wall_s)
        if not data:
            if now - self._heard_wall > SILENT_WALL_S:
                raise Failed(f"the vehicle said nothing for {SILENT_WALL_S:g} s (wall)")
            return
        self._heard_wall = now
        for m in self.codec.parse_buffer(data) or []:
            self._take(m)

    def _take(self, m) -> None:
        kind = m.get_type()
        if hasattr(m, "time_boot_ms"):
            self.vehicle_ms = max(self.vehicle_ms, m.time_boot_ms)
        if kind == "HEARTBEAT":
            if m.autopilot == mav.MAV_AUTOPILOT_INVALID or m.get_srcComponent() != 1:
                return
            self.sysid = m.get_srcSystem()
            self.mode = m.custom_mode
            self.armed = bool(m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
        elif kind == "GLOBAL_POSITION_INT":
            self.pos_ne = latlon_e7_to_ne(*self.home, m.lat, m.lon)
            self.rel_alt_m = m.relative_alt * 1e-3
            self.vel_ne = (m.vx * 0.01, m.vy * 0.01)
        elif kind == "COMMAND_ACK":
            self.acks[m.command] = m.result
        elif kind == "MISSION_ITEM_REACHED":
            self.reached.add(m.seq)
        elif kind == "STATUSTEXT":
            self.texts.append(m.text)
        elif kind in ("MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"):
            self._inbox.append(m)

    def wait_until(self, done, sim_s: float, what: str) -> float:
        """Pump until done() (returns the clock then) or sim_s of sim time pass (Failed)."""
        end = self.clock() + sim_s
        while not done():
            if self.clock() > end:
                raise TimedOut(f"{what}: not within {sim_s:g} s of sim time"
                             + (f"; the vehicle said: {' | '.join(self.texts[-3:])}"
                                if self.texts else ""))
            self.pump()
        return self.clock()

    def hold(self, sim_s: float, each=None, every_s: float = 0.1) -> None:
        """Pump for sim_s of sim time, calling each() every every_s of it."""
        end = self.clock() + sim_s
        next_call = self.clock()
        while self.clock() < end:
            if each is not None and self.clock() >= next_call:
                each()
                next_call = self.clock() + every_s
            self.pump()

    # ---- commands --------------------------------------------------------------------------
    def command(self, cmd: int, *params, sim_s: float = 5.0) -> int:
        """COMMAND_LONG, resent each second of sim time until acknowledged; the result."""
        p = list(params) + [0.0] * (7 - len(params))
        return self._until_acked(cmd, lambda: self.codec.command_long_send(
            self.sysid or 1, 1, cmd, 0, *p), sim_s)

    def command_int(self, cmd: int, frame: int, p1: float, p2: float, p3: float, p4: float,
                    x: int, y: int, z: float, sim_s: float = 5.0) -> int:
        """COMMAND_INT, resent each second of sim time until acknowledged; the result."""
        return self._until_acked(cmd, lambda: self.codec.command_int_send(
            self.sysid or 1, 1, frame, cmd, 0, 0, p1, p2, p3, p4, x, y, z), sim_s)

    def _until_acked(self, cmd: int, send, sim_s: float) -> int:
        self.acks.pop(cmd, None)
        end = self.clock() + sim_s
        while self.clock() < end:
            send()
            try:
                self.wait_until(lambda: cmd in self.acks, 1.0, "ack")
                return self.acks[cmd]
            except TimedOut:    # resend; a silent vehicle's clock stands still: not this
                continue
        raise Failed(f"no COMMAND_ACK for command {cmd}")

    def start(self, sim_s: float = 60.0) -> None:
        """First heartbeat, then the streams the sequencing reads."""
        self.wait_until(lambda: self.sysid is not None, sim_s, "a heartbeat")
        self.codec.request_data_stream_send(self.sysid, 1, mav.MAV_DATA_STREAM_ALL, 10, 1)
        self.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
                     1e6 / POSITION_HZ)

    def position_target(self, north_m: float, east_m: float, alt_m: float) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT, position only, alt_m above home."""
        lat, lon = ne_to_latlon_e7(*self.home, north_m, east_m)
        self.codec.set_position_target_global_int_send(
            0, self.sysid, 1, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, MASK_POSITION_ONLY,
            lat, lon, alt_m, 0, 0, 0, 0, 0, 0, 0, 0)

    def velocity(self, vn: float, ve: float, yaw_rad: float) -> None:
        """SET_POSITION_TARGET_LOCAL_NED, velocity and yaw."""
        self.codec.set_position_target_local_ned_send(
            0, self.sysid, 1, mav.MAV_FRAME_LOCAL_NED, MASK_VELOCITY_YAW,
            0, 0, 0, vn, ve, 0, 0, 0, 0, yaw_rad, 0)

    def distance_to(self, north_m: float, east_m: float) -> float:
        return math.hypot(self.pos_ne[0] - north_m, self.pos_ne[1] - east_m)

    def speed(self) -> float:
        return math.hypot(*self.vel_ne)

    # ---- missions --------------------------------------------------------------------------
    def upload_mission(self, items: list[dict], sim_s: float = 30.0) -> None:
        """MISSION_COUNT, each MISSION_ITEM_INT asked for, the final MISSION_ACK accepted."""
        self._inbox.clear()
        self.codec.mission_count_send(self.sysid, 1, len(items), mav.MAV_MISSION_TYPE_MISSION)
        end = self.clock() + sim_s
        while self.clock() < end:
            self.pump()
            while self._inbox:
                m = self._inbox.pop(0)
                if m.get_type() == "MISSION_ACK":
                    if m.type != mav.MAV_MISSION_ACCEPTED:
                        name = mav.enums["MAV_MISSION_RESULT"].get(m.type)
                        raise Unsupported(f"mission refused: MISSION_ACK "
                                          f"{name.name if name else m.type}")
                    return
                it = items[m.seq]
                self.codec.mission_item_int_send(
                    self.sysid, 1, m.seq, it["frame"], it["command"], 0, 1, it.get("p1", 0.0),
                    0.0, 0.0, 0.0, it["x"], it["y"], it["z"], mav.MAV_MISSION_TYPE_MISSION)
        raise Failed("mission upload: no MISSION_ACK")

    def mission_item(self, command: int, north_m: float, east_m: float, alt_m: float) -> dict:
        lat, lon = ne_to_latlon_e7(*self.home, north_m, east_m)
        return {"frame": mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, "command": command,
                "x": lat, "y": lon, "z": alt_m}
