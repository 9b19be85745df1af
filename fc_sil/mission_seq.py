"""Which mission item runs next: ArduPilot's mission cursor (AP_Mission), DO_JUMP included.

Items are the MissionStore's tuple (seq 0 is home, never run). Two kinds of command run side
by side, as in ArduCopter:

* one navigation command (id <= MAV_CMD_NAV_LAST: waypoints, take-off, loiters, RTL, LAND,
  NAV_DELAY) at a time; MISSION_CURRENT reports its seq;
* the DO / CONDITION commands found between the previous navigation command and this one,
  one at a time, while this one flies: a CONDITION_DELAY holds back the DO commands after it,
  never the navigation.

DO_JUMP is never run itself: the search for the next command follows it to its target
(p1) while it has been taken fewer than p2 times (-1 = for ever) and counts one use each
time the *navigation* cursor passes it ("Mission: <seq> Jump <n>/<total>"); look-ahead
searches (the next leg of a spline) follow it without counting. A jump to seq 0 or past the
end, or a loop of jumps with no navigation command, ends the mission.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

JUMP_FOREVER = -1
MAX_JUMP_FOLLOWS = 64        # AP_Mission: a search follows at most this many jumps
MAX_NAV_SEARCH = 255         # and advances over at most this many commands


def is_nav(command: int) -> bool:
    return command <= mav.MAV_CMD_NAV_LAST


class MissionCursor:
    def __init__(self, items=()):
        self.items = tuple(items)
        self.reset()

    def reset(self) -> None:
        """Back to the start: no command loaded, every jump unused."""
        self.nav_index = 0            # 0: none loaded yet
        self.do_index = 0
        self.do_loaded = False
        self.do_all_done = False
        self.jumps_run: dict[int, int] = {}
        self.texts: list[str] = []    # statustexts for the vehicle to send

    # ---- searching --------------------------------------------------------------------

    def next_cmd(self, start: int, count_jumps: bool) -> int | None:
        """Index of the first non-jump command at or after `start`, following DO_JUMPs."""
        i = start
        follows = 0
        first_jump = None
        while 0 < i < len(self.items):
            it = self.items[i]
            if it.command != mav.MAV_CMD_DO_JUMP:
                return i
            follows += 1
            target = int(it.param1)
            times = int(it.param2)
            if follows > MAX_JUMP_FOLLOWS or not 0 < target < len(self.items):
                return None
            if not count_jumps and first_jump == i:
                return None            # the same jump twice in one look-ahead: a dead loop
            first_jump = i if first_jump is None else first_jump
            if times == JUMP_FOREVER:
                i = target
            elif self.jumps_run.get(i, 0) < times:
                if count_jumps:
                    self.jumps_run[i] = self.jumps_run.get(i, 0) + 1
                    self.texts.append(f"Mission: {i} Jump {self.jumps_run[i]}/{times}")
                i = target
            else:
                i += 1
        return None

    def next_nav(self, start: int) -> int | None:
        """The navigation command the mission would run at or after `start` (no jump used)."""
        i = start
        for _ in range(MAX_NAV_SEARCH):
            j = self.next_cmd(i, count_jumps=False)
            if j is None:
                return None
            if is_nav(self.items[j].command):
                return j
            i = j + 1
        return None

    # ---- moving on --------------------------------------------------------------------

    def advance_nav(self, start: int | None = None) -> tuple[int | None, int | None]:
        """Load the next navigation command (from `start`, else after the current one) and
        the first DO command met on the way. Returns (nav index or None = mission over,
        DO index to start or None)."""
        i = start if start is not None else (self.nav_index + 1 if self.nav_index else 1)
        self.do_loaded = False
        self.do_all_done = False
        first_do = None
        for _ in range(MAX_NAV_SEARCH):
            j = self.next_cmd(i, count_jumps=True)
            if j is None:
                return None, first_do
            if is_nav(self.items[j].command):
                self.nav_index = j
                if first_do is None:
                    self.do_all_done = True
                return j, first_do
            if first_do is None:
                first_do = j
                self.do_index = j
                self.do_loaded = True
            i = j + 1
        return None, first_do

    def advance_do(self) -> int | None:
        """The DO command after the current one, up to the next navigation command."""
        if self.do_all_done:
            return None
        start = self.do_index + 1 if self.do_index else 1
        j = self.next_cmd(start, count_jumps=False) if start < len(self.items) else None
        if j is None or is_nav(self.items[j].command):
            self.do_all_done = True
            return None
        self.do_index = j
        self.do_loaded = True
        return j

    def starts_with_takeoff(self, start: int) -> bool:
        """ArduCopter's check before AUTO from the ground (NAV_DELAY may come first)."""
        i = start
        for _ in range(16):
            j = self.next_nav(i)
            if j is None:
                return False
            c = self.items[j].command
            if c == mav.MAV_CMD_NAV_TAKEOFF:
                return True
            if c != mav.MAV_CMD_NAV_DELAY:
                return False
            i = j + 1
        return False
