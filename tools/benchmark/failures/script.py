"""The client's flight of a failure plan, identical for every autopilot: take off (nav's
ways), hold, start the phase at PHASE_AT_S (a mission: AUTO; a hold: nothing to send),
then watch through the fault without a command until the vehicle has landed and disarmed
or the plan's end_s. The client never reacts to the fault: what happens is the
autopilot's doing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.tools.benchmark.failures.plans import ALT_M, MISSION_NE, PHASE_AT_S, PlanRun
from silbridge.tools.benchmark.failures.watch import FailureClient, Timeline
from silbridge.tools.benchmark.nav.client import Failed, Unsupported
from silbridge.tools.benchmark.nav.ways import ArduCopterWays

DISARMED_END_S = 2.0      # after a disarm past the fault, watch this long, then end [s]


@dataclass
class FailureFlight:
    """What the client did and saw (sim seconds, the run log's clock)."""
    status: str = "ok"                  # ok, unsupported, failed, not_in_phase
    reason: str = ""
    takeoff_s: float = math.nan
    phase_s: float = math.nan           # the phase started (AUTO entered; hold: PHASE_AT_S)
    end_s: float = math.nan
    timeline: Timeline = field(default_factory=Timeline)
    muted_writes: int = 0
    sim_params: list = field(default_factory=list)   # ArduCopter: (t_s, values) sent


def fly_failure(run: PlanRun, client: FailureClient, ways=None) -> FailureFlight:
    """Fly run.plan; a refusal or a missed phase is the flight's status, not an exception."""
    plan = run.plan
    ways = ways or ArduCopterWays()
    f = FailureFlight()
    try:
        client.start()
        f.takeoff_s = ways.take_off(client, ALT_M)
        if plan.phase == "mission":
            client.upload_mission(ways.mission(client, [
                client.mission_item(mav.MAV_CMD_NAV_WAYPOINT, n, e, ALT_M) for n, e in MISSION_NE]))
        if client.clock() > PHASE_AT_S:
            raise Failed(f"airborne only at {client.clock():.0f} s, after the phase start "
                         f"({PHASE_AT_S:g} s)")
        client.hold(PHASE_AT_S - client.clock())
        f.phase_s = client.clock()
        if plan.phase == "mission":
            ways.start_mission(client)
        _watch(plan, client)
    except Unsupported as e:
        f.status, f.reason = "unsupported", str(e)
    except Failed as e:
        f.status, f.reason = "failed", str(e)
    except OSError as e:        # the autopilot's MAVLink connection went (its process ended)
        f.status, f.reason = "failed", f"MAVLink connection lost: {e}"
    f.end_s = client.clock()
    f.timeline = client.timeline
    f.muted_writes = client.dropped
    return f


def _watch(plan, client: FailureClient) -> None:
    """Pump until end_s, or DISARMED_END_S after a disarm that follows the fault."""
    disarmed_at = None
    while client.clock() < plan.end_s:
        client.pump()
        if client.clock() >= plan.fault_on_s and not client.armed:
            disarmed_at = client.clock() if disarmed_at is None else disarmed_at
            if client.clock() - disarmed_at >= DISARMED_END_S:
                return
        else:
            disarmed_at = None
