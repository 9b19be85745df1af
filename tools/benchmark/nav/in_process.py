"""What the runs whose physics serves in this process share (ArduCopter, PX4): the
ground-truth log the physics writes, and the client's flight in a thread beside it.
"""

from __future__ import annotations

import threading

from silbridge.shm.records import Kind
from silbridge.tools.benchmark.nav.client import NavClient
from silbridge.tools.benchmark.nav.link import LinkError
from silbridge.tools.benchmark.nav.plans import Plan
from silbridge.tools.benchmark.nav.scripts import Flight, fly_plan

_GT_KINDS = (int(Kind.GT_NAV), int(Kind.GT_ATT))
BOOT_SLACK_S = 200.0          # sim seconds for boot, EKF, arming and take-off on top of a plan


class GroundTruthLog:
    """The physics' sink: /gt_nav and /gt_att of every step, on the physics clock."""

    def __init__(self, path: str, metadata: dict):
        from silbridge.tools.logs.mcap_log import LogWriter
        self.writer = LogWriter(path, metadata=metadata, viz_hz=0)

    def step(self, recs, pwm, sim) -> None:
        kind = recs["kind"]
        self.writer.write_records(recs[(kind == _GT_KINDS[0]) | (kind == _GT_KINDS[1])])

    def timing(self, *row) -> None:
        """The link's timing: not part of this benchmark."""

    def close(self, **summary) -> None:
        self.writer.close(**summary)


def fly_autopilot_thread(plan: Plan, make_link, home, clock, stop=None, ways=None
                         ) -> tuple[threading.Thread, dict]:
    """The client's flight in a thread (the physics serves in the caller's); out["flight"]
    holds the Flight when done, out["done"] says so. ways: tools/benchmark/nav/ways.py."""
    out: dict = {"done": False}

    def body():
        link = None
        try:
            link = make_link()
            out["flight"] = fly_plan(plan, NavClient(link, *home, clock=clock, stop=stop), ways)
        except LinkError as e:
            out["flight"] = Flight(status="failed", reason=str(e))
        finally:
            if link is not None:
                link.close()
            out["done"] = True
    return threading.Thread(target=body, daemon=True, name=f"nav-{plan.name}"), out
