"""The client's flight of each plan, identical for every controller: take off in GUIDED,
then the plan, noting on the sim clock when each command went out (the scores cut the
ground truth at those times).

N1: each goto is sent once (as a script's `goto_location` would); the next one follows when
the vehicle reports itself within ARRIVE_REPORT_M and slower than SETTLED_M_S, plus the
plan's hold. N2: each velocity leg is resent at RESEND_HZ of sim time (ArduCopter drops a
velocity target after 3 s without one) for its duration. N3/N4: the mission is uploaded,
AUTO entered, and the run ends when the vehicle reports the last item reached (or is
within ARRIVE_REPORT_M of it), plus the hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.benchmark.nav.client import Failed, NavClient, Unsupported
from silbridge.tools.benchmark.nav.plans import ALT_M, Plan
from silbridge.tools.benchmark.nav.scoring import PASS_M
from silbridge.tools.benchmark.nav.ways import ArduCopterWays

ARRIVE_REPORT_M = 0.5     # N1/N3 sequencing: reported distance to the target [m]
SETTLED_M_S = 0.3         # N1 sequencing: reported speed below this [m/s]
RESEND_HZ = 10.0          # N2: velocity targets per second of sim time


@dataclass
class Flight:
    """What the client did and when (sim seconds, the run log's clock)."""
    status: str = "ok"                  # ok, unsupported, failed
    reason: str = ""
    takeoff_s: float = math.nan
    sent_s: list = field(default_factory=list)   # N1/N2: each command; N3: AUTO entered
    end_s: float = math.nan             # the end of the scored flight
    texts: list = field(default_factory=list)


def fly_plan(plan: Plan, client: NavClient, ways=None) -> Flight:
    """Fly plan the autopilot's ways (tools/benchmark/nav/ways.py; default ArduCopter's); a
    refusal or a missed target ends the flight with its status, not an exception (the
    suite goes on with the next run)."""
    ways = ways or ArduCopterWays()
    f = Flight()
    try:
        client.start()
        f.takeoff_s = ways.take_off(client, ALT_M)
        {"goto": _gotos, "velocity": _velocity_box, "mission": _mission}[plan.kind](
            plan, client, ways, f, client.clock() + plan.budget_s)
    except Unsupported as e:
        f.status, f.reason = "unsupported", str(e)
    except Failed as e:
        f.status, f.reason = "failed", str(e)
    f.end_s = client.clock() if not math.isfinite(f.end_s) else f.end_s
    f.texts = client.texts[-10:]
    return f


def _left(client: NavClient, deadline_s: float, what: str) -> float:
    left = deadline_s - client.clock()
    if left <= 0:
        raise Failed(f"{what}: the plan's budget ran out")
    return left


def _gotos(plan: Plan, client: NavClient, ways, f: Flight, deadline_s: float) -> None:
    for g in plan.steps:
        f.sent_s.append(client.clock())
        ways.goto(client, g.north_m, g.east_m, ALT_M)
        client.wait_until(lambda: client.distance_to(g.north_m, g.east_m) < ARRIVE_REPORT_M
                          and client.speed() < SETTLED_M_S,
                          _left(client, deadline_s, "goto"),
                          f"goto ({g.north_m:g}, {g.east_m:g}) m")
        client.hold(plan.hold_s)
    f.end_s = client.clock()


def _velocity_box(plan: Plan, client: NavClient, ways, f: Flight, deadline_s: float) -> None:
    ways.start_velocity(client)
    for leg in plan.steps:
        f.sent_s.append(client.clock())
        _left(client, deadline_s, "velocity box")
        client.hold(leg.duration_s, lambda: ways.velocity(client, leg.vn_m_s, leg.ve_m_s,
                                                          math.radians(leg.yaw_deg)),
                    every_s=1.0 / RESEND_HZ)
    f.end_s = client.clock()


def _mission(plan: Plan, client: NavClient, ways, f: Flight, deadline_s: float) -> None:
    items = ways.mission(client, [client.mission_item(
        mav.MAV_CMD_NAV_SPLINE_WAYPOINT if w.spline else mav.MAV_CMD_NAV_WAYPOINT,
        w.north_m, w.east_m, ALT_M) for w in plan.steps])
    client.upload_mission(items)
    client.reached.clear()
    f.sent_s.append(client.clock())
    ways.start_mission(client)
    last, before = plan.steps[-1], plan.steps[-2]
    seen_before = [False]

    def done() -> bool:
        seen_before[0] |= client.distance_to(before.north_m, before.east_m) < PASS_M
        return len(items) - 1 in client.reached or (
            seen_before[0] and client.distance_to(last.north_m, last.east_m) < ARRIVE_REPORT_M)
    client.wait_until(done, _left(client, deadline_s, "mission"), "mission complete")
    client.hold(plan.hold_s)
    f.end_s = client.clock()
