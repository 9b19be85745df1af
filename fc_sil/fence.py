"""Geofence: ArduCopter 4.6's AC_Fence for this vehicle (FENCE_* parameters, uploaded fence).

Fences (FENCE_TYPE bits): 1 max altitude above home (FENCE_ALT_MAX), 2 circle about home
(FENCE_RADIUS), 4 the uploaded inclusion/exclusion polygons and circles (mission type FENCE,
mavlink/gcs/geo_store.py), 8 min altitude (FENCE_ALT_MIN). The vehicle must stay inside every
inclusion shape (inside any one of them with FENCE_OPTIONS bit 1) and outside every exclusion.

Checked every outer-loop step, armed or not (a breach on the ground fails the pre-arm check
"Vehicle breaching Polygon fence"). Armed, a new breach is announced ("Max Alt fence breached", "Circle fence
breached", "Polygon fence breached", NOTICE) and, armed and with FENCE_ACTION set, acted on as
Copter::fence_check does: on the ground -> disarm; more than 100 m outside -> LAND; else
1 RTL (LAND if RTL refuses), 2 LAND, 3 RTL or LAND (no SmartRTL here), 4 BRAKE or LAND,
5 LAND. As in AC_Fence, the altitude and circle fences then move 20 m out (a "backup fence")
so a vehicle that keeps going triggers again (a breach clears once 1 m back inside, so noise
on the line does not flap it), and a mode change while breached (the action's
own, or the pilot's) starts a 10 s manual recovery during which breaches are recorded but not
acted on ("Manual recovery started"). When every breach clears: "Fence breach cleared".

SYS_STATUS GEOFENCE bit (AC_Fence::sys_status_*): present when a fence type is selected (the
polygon type only with an uploaded fence), enabled when present, enabled and FENCE_ACTION is
not report-only, healthy unless present and breached. FENCE_STATUS is sent while enabled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.geo_store import FENCE_CIRCLE
from silbridge.mavlink.gcs.vehicle_api import CopterMode
from silbridge.shm.records import NS_PER_S as _NS

ALT_MAX, CIRCLE, POLYGON, ALT_MIN = 1, 2, 4, 8
BACKUP_M = 20.0                 # AC_FENCE_*_BACKUP_DISTANCE (copter)
GIVE_UP_M = 100.0               # AC_FENCE_GIVE_UP_DISTANCE: farther out, just land
RECOVERY_S = 10.0               # AC_FENCE_MANUAL_RECOVERY_TIME_MIN
CLEAR_M = 1.0                   # ours: a breach clears 1 m inside (no flapping on estimate noise)
NAMES = ((ALT_MAX, "Max Alt"), (ALT_MIN, "Min Alt"), (CIRCLE, "Circle"), (POLYGON, "Polygon"))
NOTICE, INFO = mav.MAV_SEVERITY_NOTICE, mav.MAV_SEVERITY_INFO


@dataclass(frozen=True)
class FenceConfig:
    enable: int = 0
    types: int = 7
    action: int = 1
    alt_max: float = 100.0
    alt_min: float = -10.0
    radius: float = 300.0
    margin: float = 2.0
    auto_enable: int = 0
    options: int = 0

    @classmethod
    def from_store(cls, get) -> "FenceConfig":
        return cls(enable=int(get("FENCE_ENABLE")), types=int(get("FENCE_TYPE")),
                   action=int(get("FENCE_ACTION")), alt_max=get("FENCE_ALT_MAX"),
                   alt_min=get("FENCE_ALT_MIN"), radius=get("FENCE_RADIUS"),
                   margin=get("FENCE_MARGIN"), auto_enable=int(get("FENCE_AUTOENABLE")),
                   options=int(get("FENCE_OPTIONS")))


@dataclass(frozen=True)
class Shape:
    inclusion: bool
    circle: bool
    points_e7: tuple[tuple[int, int], ...]    # polygon vertices, or the circle's centre
    radius_m: float = 0.0


def shapes_from_items(items) -> tuple[Shape, ...]:
    """The uploaded fence list (already validated by geo_store) as shapes."""
    out, i = [], 0
    while i < len(items):
        it = items[i]
        if it.command in FENCE_CIRCLE:
            out.append(Shape(it.command == mav.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, True,
                             ((it.x, it.y),), float(it.param1)))
            i += 1
        else:
            n = int(it.param1)
            out.append(Shape(it.command == mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                             False, tuple((p.x, p.y) for p in items[i:i + n])))
            i += n
    return tuple(out)


def _inside_polygon(p, poly) -> bool:
    """Even-odd ray test in a local metric frame."""
    x, y = p
    inside = False
    j = len(poly) - 1
    for i in range(len(poly)):
        xi, yi = poly[i]
        xj, yj = poly[j]
        if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
            inside = not inside
        j = i
    return inside


class Geofence:
    def __init__(self):
        self.cfg = FenceConfig()
        self.shapes: tuple[Shape, ...] = ()
        self.breaches = 0
        self.breach_count = 0
        self.breach_type = mav.FENCE_BREACH_NONE
        self.breach_time_ms = 0
        self._backup = {ALT_MAX: 0.0, ALT_MIN: 0.0, CIRCLE: 0.0}
        self._distance = {ALT_MAX: 0.0, ALT_MIN: 0.0, CIRCLE: 0.0}
        self._recovery_until_ns = None

    # ---- configuration -------------------------------------------------------------------
    def configure(self, get) -> None:
        self.cfg = FenceConfig.from_store(get)

    def set_items(self, items) -> None:
        self.shapes = shapes_from_items(items)

    # ---- state read by SYS_STATUS, FENCE_STATUS and the pre-arm check --------------------
    def present(self) -> bool:
        t = self.cfg.types
        return bool(t & (CIRCLE | ALT_MIN | ALT_MAX) or (t & POLYGON and self.shapes))

    def enabled(self, v) -> bool:
        """The master switch, FENCE_ENABLE or its auto-enable condition."""
        c = self.cfg
        if c.enable:
            return True
        if c.auto_enable == 3:
            return v.armed
        if c.auto_enable in (1, 2):
            return v.armed and v.airborne and not v.takeoff_in_progress \
                and not (c.auto_enable == 1 and v.landing)
        return False

    def sys_status(self, v) -> tuple[bool, bool, bool]:
        """(present, enabled, healthy) of MAV_SYS_STATUS_GEOFENCE."""
        present = self.present()
        enabled = present and self.cfg.action != 0 and self.enabled(v)
        return present, enabled, not (present and self.breaches)

    def prearm_failure(self, v) -> str | None:
        c = self.cfg
        on = self.enabled(v) or c.auto_enable != 0
        if c.enable and not self.present():
            return "PreArm: Fences enabled, but none selected"
        if not on or not c.types:
            return None
        if c.types & (CIRCLE | POLYGON) and not (v.home_set and v.position_ok()):
            return "PreArm: Fence requires position"
        if c.types & POLYGON and any(s.inclusion and s.circle and s.radius_m < c.margin
                                     for s in self.shapes):
            return "PreArm: Margin is less than inclusion circle radius"
        if c.types & CIRCLE:
            if c.radius < 0:
                return "PreArm: Invalid FENCE_RADIUS value"
            if c.radius < c.margin:
                return "PreArm: Circle FENCE_MARGIN is less than FENCE_RADIUS"
        if c.alt_max < 0.0:
            return "PreArm: Invalid FENCE_ALT_MAX value"
        if c.alt_min < -100.0:
            return "PreArm: Invalid FENCE_ALT_MIN value"
        if self.breaches:
            name = next(n for bit, n in NAMES if self.breaches & bit)
            return f"PreArm: Vehicle breaching {name} fence"
        if c.margin < 0.0:
            return "PreArm: Invalid FENCE_MARGIN value"
        if c.alt_max < c.alt_min:
            return "PreArm: FENCE_ALT_MAX < FENCE_ALT_MIN"
        if c.alt_max - c.alt_min <= 2.0 * c.margin:
            return "PreArm: FENCE_MARGIN too big"
        return None

    # ---- geometry ------------------------------------------------------------------------
    def _local(self, v, lat_e7: int, lon_e7: int) -> tuple[float, float]:
        return v.est.origin.to_ne(lat_e7, lon_e7)

    def _polygon_breached(self, v, ne) -> bool:
        inclusions, excluded = [], False
        for s in self.shapes:
            if s.circle:
                c = self._local(v, *s.points_e7[0])
                inside = math.hypot(ne[0] - c[0], ne[1] - c[1]) < s.radius_m
            else:
                inside = _inside_polygon(ne, [self._local(v, *p) for p in s.points_e7])
            if s.inclusion:
                inclusions.append(inside)
            elif inside:
                excluded = True
        if excluded:
            return True
        if not inclusions:
            return False
        return not any(inclusions) if self.cfg.options & 2 else not all(inclusions)

    def safe_alt_max(self, v) -> float | None:
        """Highest altitude RTL may use (AC_Fence::get_safe_alt_max), None without the fence."""
        if self.enabled(v) and self.cfg.types & ALT_MAX:
            return self.cfg.alt_max - self.cfg.margin
        return None

    def destination_ok(self, v, ne, alt_m: float) -> bool:
        """AC_Fence::check_destination_within_fence: GUIDED refuses targets outside."""
        if not self.enabled(v):
            return True
        t, c = self.cfg.types, self.cfg
        alt_m -= v.home_up_m            # the fence's altitudes are above home
        if t & ALT_MAX and alt_m > c.alt_max:
            return False
        if t & ALT_MIN and alt_m < c.alt_min:
            return False
        if t & CIRCLE and math.hypot(ne[0] - v.home_ne[0], ne[1] - v.home_ne[1]) > c.radius:
            return False
        if t & POLYGON and v.est.origin is not None and self._polygon_breached(v, ne):
            return False
        return True

    # ---- the check -----------------------------------------------------------------------
    def _limit(self, kind: int, value: float, limit: float, above: bool) -> int:
        """1 new breach (or backup fence crossed), 0 otherwise; keeps the breach bit."""
        out = value >= limit if above else value <= limit
        if not out and self.breaches & kind and abs(value - limit) < CLEAR_M:
            return 0            # hovering on the line: not cleared yet
        if not out:
            self.breaches &= ~kind
            self._backup[kind] = 0.0
            self._distance[kind] = 0.0
            return 0
        self._distance[kind] = abs(value - limit)
        backup = self._backup[kind]
        if not self.breaches & kind or (backup and (value >= backup if above
                                                    else value <= backup)):
            self._backup[kind] = value + BACKUP_M if above else value - BACKUP_M
            return kind
        return 0

    def check(self, v) -> None:
        c = self.cfg
        if not self.enabled(v) or not c.types:
            if self.breaches:
                self.breaches = 0
                self.breach_type = mav.FENCE_BREACH_NONE
            return
        before = self.breaches
        new = 0
        above_home_m = v.alt_m - v.home_up_m
        if c.types & ALT_MAX:
            new |= self._limit(ALT_MAX, above_home_m, c.alt_max, True)
        else:
            self.breaches &= ~ALT_MAX
        floor_on = not (c.auto_enable == 2 and v.landing)
        if c.types & ALT_MIN and floor_on:
            new |= self._limit(ALT_MIN, above_home_m, c.alt_min, False)
        else:
            self.breaches &= ~ALT_MIN
        have_pos = v.home_set and v.position_ok()
        if c.types & CIRCLE and have_pos:
            d = math.hypot(v.est.pos_ne_m[0] - v.home_ne[0], v.est.pos_ne_m[1] - v.home_ne[1])
            new |= self._limit(CIRCLE, d, c.radius, True)
        elif not c.types & CIRCLE:
            self.breaches &= ~CIRCLE
        if c.types & POLYGON and self.shapes and have_pos:
            if self._polygon_breached(v, v.est.pos_ne_m):
                if not self.breaches & POLYGON:
                    new |= POLYGON
            else:
                self.breaches &= ~POLYGON
        elif not (c.types & POLYGON and self.shapes):
            self.breaches &= ~POLYGON
        if new:
            self._record(v, new)
        elif before and not self.breaches:
            self.breach_type = mav.FENCE_BREACH_NONE
            if v.armed:
                v.statustext(NOTICE, "Fence breach cleared")

    def _record(self, v, new: int) -> None:
        self.breaches |= new
        self.breach_count = min(65500, self.breach_count + 1)
        self.breach_time_ms = v.sim_ns // 1_000_000
        self.breach_type = (mav.FENCE_BREACH_MAXALT if new & ALT_MAX
                            else mav.FENCE_BREACH_MINALT if new & ALT_MIN
                            else mav.FENCE_BREACH_BOUNDARY)
        if not v.armed:
            return          # recorded (pre-arm check, FENCE_STATUS), announced only when armed
        for bit, name in NAMES:
            if new & bit:
                v.statustext(NOTICE, f"{name} fence breached")
        if self.cfg.action == 0:
            return
        if self._recovery_until_ns is not None and v.sim_ns < self._recovery_until_ns:
            return      # the pilot (or a previous action) is recovering
        self._act(v, new)

    def _act(self, v, new: int) -> None:
        if not v.airborne and not v.takeoff_in_progress:
            v.fence_disarm()        # ArduCopter: landed (land_complete) -> disarm
            return
        action = self.cfg.action
        if max((d for k, d in self._distance.items() if new & k), default=0.0) > GIVE_UP_M:
            target = [CopterMode.LAND]
        elif action == 2 or action == 5:
            target = [CopterMode.LAND]
        elif action == 4:
            target = [CopterMode.BRAKE, CopterMode.LAND]
        else:                       # 1, 3 (no SmartRTL: its fallback RTL)
            target = [CopterMode.RTL, CopterMode.LAND]
        if v.mode.number in target:
            return
        for mode in target:
            if v.fence_set_mode(mode):
                return

    def manual_recovery_start(self, v) -> None:
        """A mode change while breached: no fence action for RECOVERY_S (AC_Fence)."""
        if not self.breaches:
            return
        self._recovery_until_ns = v.sim_ns + int(RECOVERY_S * _NS)
        v.statustext(INFO, "Manual recovery started")

    def status_fields(self, v) -> dict:
        """VehicleSnapshot fields for FENCE_STATUS."""
        return dict(fence_enabled=self.enabled(v) and bool(self.cfg.types),
                    fence_breach_status=1 if self.breaches else 0,
                    fence_breach_count=self.breach_count, fence_breach_type=self.breach_type,
                    fence_breach_time_ms=self.breach_time_ms,
                    fence_mitigation=mav.FENCE_MITIGATE_NONE)
