"""A pymavlink ground station for the client tests, doing what QGroundControl does on the wire:
heartbeats at 2 Hz as system 255, REQUEST_DATA_STREAM, PARAM_SET with the echo awaited,
GUIDED + arm (retried until the autopilot's pre-arm checks pass) + take-off, and the MISSION_*
upload/download of a plan's mission, fence and rally lists (answering MISSION_REQUEST and
MISSION_REQUEST_INT alike, as ArduCopter asks with either).

Every message read is kept: STATUSTEXTs in ``texts``, the autopilot's HEARTBEAT in ``hb``.
"""

from __future__ import annotations

import time

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav

GUIDED, RTL, LAND, BRAKE = 4, 6, 9, 17


class Gcs:
    def __init__(self, url: str, timeout_s: float = 30.0):
        self.m = mavutil.mavlink_connection(url, source_system=255, source_component=190,
                                            dialect="ardupilotmega")
        self.texts: list[tuple[float, int, str]] = []
        self.hb = None
        self.last: dict[str, object] = {}
        self.seen_at: dict[str, list[float]] = {}   # every message type: when each arrived
        self.breach_types: set[int] = set()      # FENCE_STATUS.breach_type seen while breached
        self.fence_unhealthy = False             # SYS_STATUS geofence present but unhealthy
        self._next_hb = 0.0
        if self.wait("HEARTBEAT", lambda h: h.get_srcComponent() == 1, timeout_s) is None:
            raise AssertionError(f"no heartbeat from the autopilot at {url}")

    # ---- the pump ------------------------------------------------------------------------
    def _heartbeat(self) -> None:
        now = time.monotonic()
        if now >= self._next_hb:
            self.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            self._next_hb = now + 0.5

    def _take(self, x) -> None:
        t = x.get_type()
        self.last[t] = x
        self.seen_at.setdefault(t, []).append(time.monotonic())
        if t == "STATUSTEXT":
            self.texts.append((time.monotonic(), x.severity, x.text))
        elif t == "HEARTBEAT" and x.get_srcComponent() == 1 and x.get_srcSystem() == 1:
            self.hb = x
        elif t == "FENCE_STATUS" and x.breach_status:
            self.breach_types.add(x.breach_type)
        elif t == "SYS_STATUS":
            bit = mav.MAV_SYS_STATUS_GEOFENCE
            if x.onboard_control_sensors_present & bit and not \
                    x.onboard_control_sensors_health & bit:
                self.fence_unhealthy = True

    def wait(self, mtype, cond=None, timeout_s: float = 10.0):
        types = [mtype] if isinstance(mtype, str) else list(mtype)
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            self._heartbeat()
            x = self.m.recv_match(blocking=True, timeout=0.1)
            if x is None:
                continue
            self._take(x)
            if x.get_type() in types and (cond is None or cond(x)):
                return x
        return None

    def pump(self, seconds: float) -> None:
        self.wait("__none__", timeout_s=seconds)

    def collect(self, seconds: float) -> list:
        out = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._heartbeat()
            x = self.m.recv_match(blocking=True, timeout=0.1)
            if x is not None:
                self._take(x)
                out.append(x)
        return out

    def count_since(self, mtype: str, since: float) -> int:
        return sum(1 for t in self.seen_at.get(mtype, ()) if t >= since)

    def wait_seen(self, mtype: str, since: float, timeout_s: float) -> bool:
        """True once a message of mtype has arrived at or after `since` (already or later)."""
        end = time.monotonic() + timeout_s
        while self.count_since(mtype, since) == 0 and time.monotonic() < end:
            self.pump(0.1)
        return self.count_since(mtype, since) > 0

    def text_seen(self, needle: str, since: float = 0.0) -> bool:
        return any(needle in t for ts, _, t in self.texts if ts >= since)

    # ---- commands and parameters ---------------------------------------------------------
    def command(self, cmd: int, *p, timeout_s: float = 5.0):
        p = list(p) + [0.0] * (7 - len(p))
        self.m.mav.command_long_send(1, 1, cmd, 0, *p)
        return self.wait("COMMAND_ACK", lambda a: a.command == cmd, timeout_s)

    def set_param(self, name: str, value: float, timeout_s: float = 5.0) -> float:
        for _ in range(3):
            self.m.mav.param_set_send(1, 1, name.encode(), float(value),
                                      mav.MAV_PARAM_TYPE_REAL32)
            r = self.wait("PARAM_VALUE", lambda p: p.param_id == name, timeout_s)
            if r is not None:
                return r.param_value
        raise AssertionError(f"no PARAM_VALUE echo for {name}")

    def get_param(self, name: str, timeout_s: float = 5.0) -> float | None:
        self.m.mav.param_request_read_send(1, 1, name.encode(), -1)
        r = self.wait("PARAM_VALUE", lambda p: p.param_id == name, timeout_s)
        return None if r is None else r.param_value

    def streams(self, hz: int = 10) -> None:
        self.m.mav.request_data_stream_send(1, 1, mav.MAV_DATA_STREAM_ALL, hz, 1)

    def mode(self) -> int | None:
        return None if self.hb is None else self.hb.custom_mode

    def armed(self) -> bool:
        return bool(self.hb is not None and self.hb.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)

    def wait_mode(self, mode: int, timeout_s: float) -> bool:
        return self.wait("HEARTBEAT", lambda h: h.get_srcComponent() == 1
                         and h.custom_mode == mode, timeout_s) is not None

    def arm_and_takeoff(self, alt_m: float, timeout_s: float = 90.0) -> None:
        """GUIDED, arm (retried while the pre-arm checks still fail), take off, reach alt_m-1."""
        end = time.monotonic() + timeout_s
        while not self.armed():
            if time.monotonic() > end:
                raise AssertionError(f"never armed: {self.texts[-5:]}")
            self.command(mav.MAV_CMD_DO_SET_MODE, 1, GUIDED)
            ack = self.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            if ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED:
                self.wait("HEARTBEAT", lambda h: h.get_srcComponent() == 1
                          and h.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED, 5.0)
                break
            self.pump(1.0)
        ack = self.command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, alt_m)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, ack

    def wait_alt(self, alt_m: float, timeout_s: float) -> bool:
        return self.wait("GLOBAL_POSITION_INT", lambda p: p.relative_alt >= alt_m * 1000,
                         timeout_s) is not None

    def rtl_until_landed(self, timeout_s: float) -> object:
        """RTL, accepted and entered; pump until disarmed. The last GLOBAL_POSITION_INT."""
        ack = self.command(mav.MAV_CMD_NAV_RETURN_TO_LAUNCH)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, (ack, self.texts[-5:])
        assert self.wait_mode(RTL, 5.0)
        end = time.monotonic() + timeout_s
        while self.armed() and time.monotonic() < end:
            self.pump(0.5)
        assert not self.armed(), "RTL did not land and disarm"
        return self.last["GLOBAL_POSITION_INT"]

    def fly_velocity(self, vn: float, ve: float, seconds: float, stop=None) -> None:
        """GUIDED velocity setpoints (LOCAL_NED, velocity only), resent every 0.25 s."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.m.mav.set_position_target_local_ned_send(
                0, 1, 1, mav.MAV_FRAME_LOCAL_NED, 0x0DC7, 0, 0, 0, vn, ve, 0, 0, 0, 0, 0, 0)
            self.pump(0.25)
            if stop is not None and stop():
                return

    # ---- MISSION_* for mission, fence and rally ------------------------------------------
    def upload(self, mission_type: int, items: list, timeout_s: float = 20.0):
        """The items' seq are renumbered; returns the final MISSION_ACK (or None)."""
        self.m.mav.mission_count_send(1, 1, len(items), mission_type)
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            x = self.wait(["MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"],
                          lambda r: r.mission_type == mission_type,
                          max(0.1, end - time.monotonic()))
            if x is None:
                return None
            if x.get_type() == "MISSION_ACK":
                return x
            it = items[x.seq]
            self.m.mav.mission_item_int_send(
                1, 1, x.seq, it["frame"], it["command"], 0, 1, it.get("p1", 0.0),
                it.get("p2", 0.0), it.get("p3", 0.0), it.get("p4", 0.0), it.get("x", 0),
                it.get("y", 0), it.get("z", 0.0), mission_type)
        return None

    def download(self, mission_type: int, timeout_s: float = 20.0) -> list:
        self.m.mav.mission_request_list_send(1, 1, mission_type)
        cnt = self.wait("MISSION_COUNT", lambda c: c.mission_type == mission_type, timeout_s)
        assert cnt is not None, "no MISSION_COUNT"
        out = []
        for seq in range(cnt.count):
            it = None
            for _ in range(3):
                self.m.mav.mission_request_int_send(1, 1, seq, mission_type)
                it = self.wait("MISSION_ITEM_INT", lambda i, s=seq: i.seq == s
                               and i.mission_type == mission_type, 3.0)
                if it is not None:
                    break
            assert it is not None, f"item {seq} never came"
            out.append(it)
        self.m.mav.mission_ack_send(1, 1, mav.MAV_MISSION_ACCEPTED, mission_type)
        return out

    def clear(self, mission_type: int):
        self.m.mav.mission_clear_all_send(1, 1, mission_type)
        return self.wait("MISSION_ACK", lambda a: a.mission_type == mission_type, 5.0)

    def close(self) -> None:
        self.m.close()


def offset_e7(lat_deg: float, lon_deg: float, north_m: float, east_m: float) -> tuple[int, int]:
    import math
    lat = lat_deg + north_m / 111319.5
    lon = lon_deg + east_m / (111319.5 * math.cos(math.radians(lat_deg)))
    return int(round(lat * 1e7)), int(round(lon * 1e7))
