"""What N1..N4 fly: the points, velocity legs and missions, and the physics under them.

Positions are metres north/east of home at ALT_M above it (the ground-truth frame of the
run log, tools/benchmark/nav/geo.py). Every controller gets the same plan from the same
client (tools/benchmark/nav/scripts.py); only the link differs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

PHYSICS_DIR = Path(__file__).parent
ALT_M = 10.0               # every plan flies at this height above home [m]


@dataclass(frozen=True)
class Goto:
    """N1: one guided position target (SET_POSITION_TARGET_GLOBAL_INT, position only)."""
    north_m: float
    east_m: float


@dataclass(frozen=True)
class VelocityLeg:
    """N2: a velocity and heading held for duration_s (SET_POSITION_TARGET_LOCAL_NED)."""
    vn_m_s: float
    ve_m_s: float
    yaw_deg: float           # heading, clockwise from north
    duration_s: float


@dataclass(frozen=True)
class Waypoint:
    """N3/N4: one mission item, reached along a straight leg or a spline leg."""
    north_m: float
    east_m: float
    spline: bool             # MAV_CMD_NAV_SPLINE_WAYPOINT instead of MAV_CMD_NAV_WAYPOINT


@dataclass(frozen=True)
class Plan:
    name: str                # N1..N4
    title: str
    physics: str             # the scenario TOML in PHYSICS_DIR
    kind: str                # "goto", "velocity" or "mission"
    steps: tuple = ()
    hold_s: float = 3.0      # N1: hover after each arrival before the next target [s]
    budget_s: float = 240.0  # sim seconds the flight may take after take-off before it fails

    @property
    def physics_path(self) -> str:
        return str(PHYSICS_DIR / self.physics)


# N1: two 30 m legs at right angles, a 42 m diagonal home, then a 30 m leg west.
N1 = Plan("N1", "guided goto sequence", "nav_calm.toml", "goto",
          (Goto(30.0, 0.0), Goto(30.0, 30.0), Goto(0.0, 0.0), Goto(0.0, -30.0)))
# N2: a 3 m/s box, the nose turned to each leg's direction as the leg starts; then a stop.
N2 = Plan("N2", "offboard velocity box with yaw", "nav_calm.toml", "velocity",
          (VelocityLeg(3.0, 0.0, 0.0, 10.0), VelocityLeg(0.0, 3.0, 90.0, 10.0),
           VelocityLeg(-3.0, 0.0, 180.0, 10.0), VelocityLeg(0.0, -3.0, 270.0, 10.0),
           VelocityLeg(0.0, 0.0, 0.0, 5.0)))
# N3: a straight leg north, three spline legs round a bend, a straight leg home.
MISSION = (Waypoint(30.0, 0.0, False), Waypoint(50.0, 20.0, True), Waypoint(30.0, 40.0, True),
           Waypoint(0.0, 40.0, True), Waypoint(0.0, 0.0, False))
N3 = Plan("N3", "AUTO mission, straight and spline legs", "nav_calm.toml", "mission", MISSION)
N4 = Plan("N4", "N3 in wind with Dryden turbulence", "nav_wind.toml", "mission", MISSION)

PLANS = {p.name: p for p in (N1, N2, N3, N4)}


def plan_names(text: str) -> list[str]:
    """--scenarios of the nav suite: N1..N4, comma-separated ("all" = every one)."""
    names = [n.strip().upper() for n in text.split(",") if n.strip()]
    if names == ["ALL"]:
        return list(PLANS)
    bad = [n for n in names if n not in PLANS]
    if not names or bad:
        from silbridge.tools.benchmark.campaign import CampaignError
        raise CampaignError(f"--suite nav flies {', '.join(PLANS)}: give --scenarios "
                            f"{','.join(PLANS)} or a part of it, not {text!r}")
    return list(dict.fromkeys(names))
