"""What the runs whose physics serves in this process share (ArduCopter, PX4): the
ground-truth log the physics writes, the client's flight in a thread beside it, and the
run around both (`fly_foreign`: run_ardupilot.py and run_px4.py bring only their own parts).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

from silbridge.shm.records import Kind
from silbridge.tools.benchmark.nav.client import NavClient
from silbridge.tools.benchmark.nav.link import LinkError
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight, fly_plan
from silbridge.shm.records import NS_PER_S as _NS

_GT_KINDS = (int(Kind.GT_NAV), int(Kind.GT_ATT))
BOOT_SLACK_S = 200.0          # sim seconds for boot, EKF, arming and take-off on top of a plan


class GroundTruthLog:
    """The physics' sink: /gt_nav and /gt_att of every step, on the physics clock."""

    def __init__(self, path: str, metadata: dict):
        from silbridge.tools.logs.mcap_log import LogWriter
        self.writer = LogWriter(path, metadata=metadata, viz_hz=0)

    def step(self, recs, pwm, sim, rotor=None) -> None:
        kind = recs["kind"]
        self.writer.write_records(recs[(kind == _GT_KINDS[0]) | (kind == _GT_KINDS[1])])

    def timing(self, *row) -> None:
        """The link's timing: not part of this benchmark."""

    def close(self, **summary) -> None:
        self.writer.close(**summary)


def fly_autopilot_thread(plan: Plan, make_link, home, clock, stop=None, ways=None,
                         client_cls=NavClient, fly=fly_plan) -> tuple[threading.Thread, dict]:
    """The client's flight in a thread (the physics serves in the caller's); out["flight"]
    holds the Flight when done, out["done"] says so. ways: tools/benchmark/nav/ways.py."""
    out: dict = {"done": False}

    def body():
        link = None
        try:
            link = make_link()
            out["flight"] = fly(plan, client_cls(link, *home, clock=clock, stop=stop), ways)
        except LinkError as e:
            out["flight"] = Flight(status="failed", reason=str(e))
        finally:
            if link is not None:
                link.close()
            out["done"] = True
    return threading.Thread(target=body, daemon=True, name=f"nav-{plan.name}"), out


@dataclass
class Parts:
    """What a runner's start() opens, closed by fly_foreign whatever happened."""
    server: object = None       # the physics end's server (bridge/autopilots/*/server.py)
    sink: GroundTruthLog | None = None


def fly_foreign(plan: Plan, run, sc, start, *, stop=None, connect_timeout_s: float,
                client_cls=NavClient, fly=fly_plan) -> Flight:
    """One nav run of a foreign autopilot (run: tools/autopilots/common/run.py AutopilotRun).

    start(parts) -> (phys, make_link, ways): opens the log and the server into `parts`,
    launches the autopilot, and says how the client reaches it. The physics serves here
    until the client's flight ends; a failure on the physics side is a failed Flight that
    says why, with the autopilot's last console lines."""
    parts = Parts()
    thread, out = None, {"done": False}
    try:
        phys, make_link, ways = start(parts)
        thread, out = fly_autopilot_thread(plan, make_link, (sc.home.lat_deg, sc.home.lon_deg),
                                           lambda: phys.sim.sim_ns / _NS, stop, ways,
                                           client_cls, fly)
        thread.start()
        parts.server.serve(BOOT_SLACK_S + plan.budget_s, connect_timeout_s=connect_timeout_s,
                           stop=lambda: out["done"] or run.exited())
    except Exception as e:          # the physics side failed: a failed run, said why
        out.setdefault("flight", Flight(status="failed", reason=f"{type(e).__name__}: {e}"))
    finally:
        run.close(None, parts.server)
        if thread is not None:
            thread.join(10.0)
        if parts.sink is not None:
            parts.sink.close()
    flight = out.get("flight") or Flight(status="failed", reason="the flight did not finish "
                                         "within the physics budget")
    if flight.status == "failed" and run.tail:
        flight.reason += f"; {run.autopilot.name}'s console: {run.tail}"
    return flight
