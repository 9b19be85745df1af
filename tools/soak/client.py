"""The ground station of a soak: a pymavlink client that keeps the vehicle busy.

One thread, one connection: every wait reads (and counts) whatever arrives, so the stream
rates are measured by the same loop that runs the actions. The actions are what a ground
station does over an hour: parameter list and single reads, PARAM_SET of a gain back and
forth (saved by --save-params), mission uploads, mode changes while disarmed, stream-rate
changes. Each counts as ok or failed; a failed one is reported, not retried.
"""

from __future__ import annotations

import time
from collections import Counter

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav

# The gain written back and forth: the yaw rate D term, 0 in the defaults and not used
# while the vehicle sits disarmed on the ground.
GAIN_PARAM = "ATC_RAT_YAW_D"
GAIN_VALUES = (0.001, 0.0)
READ_PARAMS = ("ATC_RAT_RLL_P", "WPNAV_SPEED", "SYSID_THISMAV")
MODES = (("ALT_HOLD", 2), ("LOITER", 5), ("GUIDED", 4), ("STABILIZE", 0))   # CopterMode
STREAM_RATES_HZ = (4, 10)        # REQUEST_DATA_STREAM, all streams, alternately
INTERVAL_MSG = mav.MAVLINK_MSG_ID_ATTITUDE
INTERVALS_US = (50_000, 100_000)    # SET_MESSAGE_INTERVAL of ATTITUDE, alternately
ACTIONS = ("param_list", "param_read", "param_set", "mission", "mode", "streams")
# Messages whose time_boot_ms is the vehicle's (simulated) clock.
# Near the S1 scenario's home (bridge/scenarios/S1.toml); the vehicle only stores them.
HOME_LAT, HOME_LON = 47.397742, 8.545594
CLOCK_MSGS = ("ATTITUDE", "SYSTEM_TIME", "GLOBAL_POSITION_INT")


class SoakClient:
    def __init__(self, url: str, reply_timeout_s: float = 5.0):
        self.conn = mavutil.mavlink_connection(url, source_system=255, source_component=190)
        self.timeout_s = reply_timeout_s
        self.counts: Counter = Counter()      # messages by type, since the last take_counts
        self.ok: Counter = Counter()
        self.failed: Counter = Counter()
        self.failures: list[str] = []          # the first few, for the report
        self.boot_ms: int | None = None        # newest vehicle clock seen
        self._turn = 0

    # --- receiving -----------------------------------------------------------------------
    def _recv(self, timeout_s: float):
        m = self.conn.recv_match(blocking=True, timeout=timeout_s)
        if m is None or m.get_type() == "BAD_DATA":
            return None
        t = m.get_type()
        self.counts[t] += 1
        if t in CLOCK_MSGS:
            self.boot_ms = m.time_boot_ms
        return m

    def pump(self, until, timeout_s: float):
        """Read until until(msg) is true (returns that msg) or timeout (returns None)."""
        end = time.monotonic() + timeout_s
        while (left := end - time.monotonic()) > 0:
            m = self._recv(min(left, 0.2))
            if m is not None and until(m):
                return m
        return None

    def idle(self, seconds: float) -> None:
        self.pump(lambda m: False, seconds)

    def take_counts(self) -> Counter:
        c, self.counts = self.counts, Counter()
        return c

    def wait_vehicle(self, timeout_s: float) -> bool:
        hb = self.pump(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcSystem() != 255,
                       timeout_s)
        if hb is None:
            return False
        self.conn.target_system, self.conn.target_component = hb.get_srcSystem(), \
            hb.get_srcComponent()
        return True

    # --- actions ---------------------------------------------------------------------------
    def run_next(self) -> str:
        """Run the next action of the round; returns its name."""
        name = ACTIONS[self._turn % len(ACTIONS)]
        k = self._turn // len(ACTIONS)
        self._turn += 1
        try:
            err = getattr(self, f"_{name}")(k)
        except OSError as exc:          # the link itself failed (the vehicle went away)
            err = f"link error {exc}"
        if err is None:
            self.ok[name] += 1
        else:
            self.failed[name] += 1
            if len(self.failures) < 20:
                self.failures.append(f"{name}: {err}")
        return name

    def _target(self):
        return self.conn.target_system, self.conn.target_component

    def _param_list(self, k):
        self.conn.mav.param_request_list_send(*self._target())
        seen, total = set(), [None]

        def got_all(m):
            if m.get_type() == "PARAM_VALUE":
                total[0] = m.param_count
                seen.add(m.param_index)
            return total[0] is not None and len(seen) >= total[0]
        if self.pump(got_all, self.timeout_s * 4) is None:
            return f"PARAM_REQUEST_LIST: {len(seen)} of {total[0]} parameters arrived"
        return None

    def _param_read(self, k):
        name = READ_PARAMS[k % len(READ_PARAMS)]
        self.conn.mav.param_request_read_send(*self._target(), name.encode(), -1)
        if self._param_value(name) is None:
            return f"PARAM_REQUEST_READ {name}: no PARAM_VALUE"
        return None

    def _param_value(self, name: str):
        return self.pump(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name,
                         self.timeout_s)

    def _param_set(self, k):
        value = GAIN_VALUES[k % len(GAIN_VALUES)]
        self.conn.mav.param_set_send(*self._target(), GAIN_PARAM.encode(), value,
                                     mav.MAV_PARAM_TYPE_REAL32)
        m = self._param_value(GAIN_PARAM)
        if m is None:
            return f"PARAM_SET {GAIN_PARAM}={value}: no PARAM_VALUE"
        if abs(m.param_value - value) > 1e-6:
            return f"PARAM_SET {GAIN_PARAM}={value}: vehicle says {m.param_value}"
        return None

    def _mission(self, k):
        items = mission_items(3 + k % 3, HOME_LAT, HOME_LON, *self._target())
        self.conn.mav.mission_count_send(*self._target(), len(items),
                                         mav.MAV_MISSION_TYPE_MISSION)

        def step(m):
            t = m.get_type()
            if t in ("MISSION_REQUEST_INT", "MISSION_REQUEST") and m.seq < len(items):
                self.conn.mav.send(items[m.seq])
            return t == "MISSION_ACK"
        ack = self.pump(step, self.timeout_s * 2)
        if ack is None:
            return "MISSION_COUNT: no MISSION_ACK"
        if ack.type != mav.MAV_MISSION_ACCEPTED:
            return f"mission upload: MISSION_ACK type {ack.type}"
        return None

    def _mode(self, k):
        name, number = MODES[k % len(MODES)]
        self.conn.mav.command_long_send(*self._target(), mav.MAV_CMD_DO_SET_MODE, 0,
                                        mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number,
                                        0, 0, 0, 0, 0)
        ack = self._ack(mav.MAV_CMD_DO_SET_MODE)
        if ack is None or ack.result != mav.MAV_RESULT_ACCEPTED:
            return f"DO_SET_MODE {name}: {'no COMMAND_ACK' if ack is None else ack.result}"
        hb = self.pump(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == number,
                       self.timeout_s)
        return None if hb is not None else f"mode {name}: HEARTBEAT never showed it"

    def _streams(self, k):
        hz = STREAM_RATES_HZ[k % len(STREAM_RATES_HZ)]
        self.conn.mav.request_data_stream_send(*self._target(), mav.MAV_DATA_STREAM_ALL,
                                               hz, 1)
        us = INTERVALS_US[k % len(INTERVALS_US)]
        self.conn.mav.command_long_send(*self._target(), mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                        INTERVAL_MSG, us, 0, 0, 0, 0, 0)
        ack = self._ack(mav.MAV_CMD_SET_MESSAGE_INTERVAL)
        if ack is None or ack.result != mav.MAV_RESULT_ACCEPTED:
            return f"SET_MESSAGE_INTERVAL: {'no COMMAND_ACK' if ack is None else ack.result}"
        return None

    def _ack(self, command: int):
        return self.pump(lambda m: m.get_type() == "COMMAND_ACK" and m.command == command,
                         self.timeout_s)

    def close(self) -> None:
        self.conn.close()


def mission_items(n: int, lat: float, lon: float, target_system: int,
                  target_component: int) -> list:
    """Home, a take-off and n-2 waypoints on a small square around (lat, lon)."""
    out = [mav.MAVLink_mission_item_int_message(
        target_system, target_component, 0, mav.MAV_FRAME_GLOBAL, mav.MAV_CMD_NAV_WAYPOINT,
        0, 1, 0, 0, 0, 0, int(lat * 1e7), int(lon * 1e7), 0, mav.MAV_MISSION_TYPE_MISSION)]
    out.append(mav.MAVLink_mission_item_int_message(
        target_system, target_component, 1, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        mav.MAV_CMD_NAV_TAKEOFF, 0, 1, 0, 0, 0, 0, 0, 0, 10, mav.MAV_MISSION_TYPE_MISSION))
    for i in range(2, n):
        d = 2e-4 * (i - 1)       # ~20 m steps
        out.append(mav.MAVLink_mission_item_int_message(
            target_system, target_component, i, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT,
            mav.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, int((lat + d) * 1e7),
            int((lon + d * (i % 2)) * 1e7), 10, mav.MAV_MISSION_TYPE_MISSION))
    return out
