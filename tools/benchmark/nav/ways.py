"""How each autopilot is asked for the same things: the mode to fly from, the take-off, a
goto, a velocity target, a mission and AUTO. Our FC takes ArduCopter's ways (its modes,
GUIDED inputs and mission protocol); PX4 has its own (PX4's custom modes, MAV_CMD_DO_REPOSITION
for a goto as MAVSDK's `goto_location` sends it, OFFBOARD for velocity targets, missions
without ArduPilot's home item).

Each way is a small object with the same verbs, chosen once per run by the harness.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.benchmark.nav.client import NavClient, Unsupported

RETRY_SIM_S = 2.0          # between attempts at a refused mode, arming or take-off [s]
TAKEOFF_BUDGET_S = 150.0   # boot, pre-arm checks and take-off, at most [sim s]
SETTLE_S = 3.0             # hover after the take-off before the plan starts [s]


def _retry_until_flying(client: NavClient, step, alt_m: float) -> float:
    """Call step() every RETRY_SIM_S while it returns a refusal text; it returns None once
    the take-off is accepted. Then reach alt_m and settle. The clock at the take-off."""
    end = client.clock() + TAKEOFF_BUDGET_S
    while True:
        t0 = client.clock()
        said = step()
        if said is None:
            break
        if client.clock() > end:
            raise Unsupported(f"no take-off within {TAKEOFF_BUDGET_S:g} s of sim time "
                              f"({said}); the vehicle said: {' | '.join(client.texts[-3:])}")
        client.hold(RETRY_SIM_S if said else 0.5)
    client.wait_until(lambda: client.rel_alt_m >= alt_m - 0.3, 40.0, "take-off altitude")
    client.hold(SETTLE_S)
    return t0


class ArduCopterWays:
    """ArduCopter 4.6 (and our FC): GUIDED, arm, MAV_CMD_NAV_TAKEOFF; GUIDED position and
    velocity targets; mission item 0 is home; AUTO."""
    GUIDED, AUTO = 4, 3                       # custom modes

    def _mode(self, client: NavClient, mode: int, name: str) -> None:
        r = client.command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mode)
        if r != mav.MAV_RESULT_ACCEPTED:
            raise Unsupported(f"mode {name} refused (result {r})")
        client.wait_until(lambda: client.mode == mode, 5.0, f"mode {name}")

    def take_off(self, client: NavClient, alt_m: float) -> float:
        """GUIDED (refused until there is a position estimate), arm (until the pre-arm
        checks pass; a vehicle left armed on the ground disarms again), take off."""
        def step():
            if client.mode != self.GUIDED:
                r = client.command(mav.MAV_CMD_DO_SET_MODE,
                                   mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, self.GUIDED)
                return "" if r == mav.MAV_RESULT_ACCEPTED else f"GUIDED: result {r}"
            if not client.armed:
                r = client.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
                return "" if r == mav.MAV_RESULT_ACCEPTED else f"arm: result {r}"
            r = client.command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, 0, 0, alt_m)
            return None if r == mav.MAV_RESULT_ACCEPTED else f"take-off: result {r}"
        return _retry_until_flying(client, step, alt_m)

    def goto(self, client: NavClient, north_m: float, east_m: float, alt_m: float) -> None:
        client.position_target(north_m, east_m, alt_m)

    def velocity(self, client: NavClient, vn: float, ve: float, yaw_rad: float) -> None:
        client.velocity(vn, ve, yaw_rad)

    def start_velocity(self, client: NavClient) -> None:
        """GUIDED takes velocity targets as they come."""

    def mission(self, client: NavClient, items: list[dict]) -> list[dict]:
        return [client.mission_item(mav.MAV_CMD_NAV_WAYPOINT, 0.0, 0.0, 0.0)] + items

    def start_mission(self, client: NavClient) -> None:
        self._mode(client, self.AUTO, "AUTO")


class Px4Ways:
    """PX4 v1.15: arm, MAV_CMD_NAV_TAKEOFF (to MIS_TAKEOFF_ALT); goto by DO_REPOSITION
    (into Hold at the point, its altitude kept); velocity targets streamed, then OFFBOARD;
    mission items from 0; AUTO.MISSION."""
    MAIN_AUTO, MAIN_OFFBOARD = 4, 6
    SUB_MISSION = 4

    @staticmethod
    def _main_sub(client: NavClient) -> tuple[int, int]:
        m = client.mode or 0
        return (m >> 16) & 0xFF, (m >> 24) & 0xFF

    def _mode(self, client: NavClient, main: int, sub: int, name: str) -> None:
        r = client.command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                           main, sub)
        if r != mav.MAV_RESULT_ACCEPTED:
            raise Unsupported(f"mode {name} refused (result {r})")
        client.wait_until(lambda: self._main_sub(client)[0] == main, 5.0, f"mode {name}")

    def take_off(self, client: NavClient, alt_m: float) -> float:
        def step():
            if not client.armed:
                r = client.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
                return "" if r == mav.MAV_RESULT_ACCEPTED else f"arm: result {r}"
            r = client.command(mav.MAV_CMD_NAV_TAKEOFF, -1, 0, 0, math.nan, math.nan,
                               math.nan, math.nan)
            return None if r == mav.MAV_RESULT_ACCEPTED else f"take-off: result {r}"
        return _retry_until_flying(client, step, alt_m)

    def goto(self, client: NavClient, north_m: float, east_m: float, alt_m: float) -> None:
        from silbridge.tools.benchmark.nav.geo import ne_to_latlon_e7
        lat, lon = ne_to_latlon_e7(*client.home, north_m, east_m)
        r = client.command_int(mav.MAV_CMD_DO_REPOSITION, mav.MAV_FRAME_GLOBAL_INT, -1,
                               mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0, math.nan, lat, lon,
                               math.nan)
        if r != mav.MAV_RESULT_ACCEPTED:
            raise Unsupported(f"MAV_CMD_DO_REPOSITION refused (result {r})")

    def velocity(self, client: NavClient, vn: float, ve: float, yaw_rad: float) -> None:
        client.velocity(vn, ve, yaw_rad)

    def start_velocity(self, client: NavClient) -> None:
        """OFFBOARD is accepted, and kept, only while targets stream (> 2 Hz): a hover
        target streams before the switch and until the heartbeat shows it."""
        def hover():
            client.velocity(0.0, 0.0, 0.0)
        client.hold(1.0, hover)
        r = client.command(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                           self.MAIN_OFFBOARD, 0)
        end = client.clock() + 5.0
        while r == mav.MAV_RESULT_ACCEPTED and self._main_sub(client)[0] != self.MAIN_OFFBOARD:
            if client.clock() > end:
                break
            client.hold(0.1, hover)
        if self._main_sub(client)[0] != self.MAIN_OFFBOARD:
            raise Unsupported(f"OFFBOARD refused (result {r})")

    def mission(self, client: NavClient, items: list[dict]) -> list[dict]:
        return items

    def start_mission(self, client: NavClient) -> None:
        self._mode(client, self.MAIN_AUTO, self.SUB_MISSION, "AUTO.MISSION")
