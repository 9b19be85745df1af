"""Rally points: where RTL goes instead of home (ArduPilot AP_Rally, as ArduCopter 4.6 uses it).

The uploaded rally list (mission type RALLY, mavlink/gcs/geo_store.py) holds MAV_CMD_NAV_RALLY_POINT
items. When RTL starts (the mode, a failsafe, a fence breach or a mission's RTL item) it flies
to ``rtl_destination``: the rally point nearest the vehicle, skipping points farther than
RALLY_LIMIT_KM from home (0 = no limit); with RALLY_INCL_HOME 1 home wins when it is closer
than that point. The point's altitude (above home in the relative frames, the way QGC sends
them; above sea level otherwise) is the altitude RTL arrives at when it is higher than RTL's
own return altitude. No usable rally point: home, as without rally points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mav

_RELATIVE = frozenset({mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                       mav.MAV_FRAME_GLOBAL_TERRAIN_ALT, mav.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT})


@dataclass(frozen=True)
class RallyPoint:
    lat_e7: int
    lon_e7: int
    alt_m: float
    relative: bool


@dataclass(frozen=True)
class RtlTarget:
    ne: tuple[float, float]
    alt_m: float | None          # above home; None = RTL's own return altitude
    rally_index: int | None      # None: home


class RallyPoints:
    def __init__(self):
        self.points: tuple[RallyPoint, ...] = ()
        self.limit_km = 0.3
        self.incl_home = 1

    def configure(self, get) -> None:
        self.limit_km = float(get("RALLY_LIMIT_KM"))
        self.incl_home = int(get("RALLY_INCL_HOME"))

    def set_items(self, items) -> None:
        self.points = tuple(RallyPoint(it.x, it.y, float(it.z), it.frame in _RELATIVE)
                            for it in items)

    def rtl_destination(self, v) -> RtlTarget:
        home = RtlTarget(tuple(v.home_ne), None, None)
        if not self.points or v.est.origin is None:
            return home
        pos = v.est.pos_ne_m
        best, best_d = None, math.inf
        for i, p in enumerate(self.points):
            ne = v.est.origin.to_ne(p.lat_e7, p.lon_e7)
            from_home = math.hypot(ne[0] - v.home_ne[0], ne[1] - v.home_ne[1])
            if self.limit_km > 0 and from_home > self.limit_km * 1000.0:
                continue
            d = math.hypot(ne[0] - pos[0], ne[1] - pos[1])
            if d < best_d:
                alt = v.alt_from_home(p.alt_m) if p.relative else v.alt_from_msl(p.alt_m)
                best, best_d = RtlTarget(ne, alt, i), d
        if best is None:
            return home
        home_d = math.hypot(v.home_ne[0] - pos[0], v.home_ne[1] - pos[1])
        if self.incl_home and home_d <= best_d:
            return home
        return best
