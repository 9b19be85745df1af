"""The cases run interleaved: round 1 runs A, B, C, ..., round 2 again A, B, C, ..., so a
machine that drifts (a thermal limit, a neighbour's job starting) slows every case alike and
the ratios between them hold, where five runs of A then five of B would not.
"""

from __future__ import annotations

from typing import Callable

from silbridge.bridge.scenario import load_scenario

from silbridge.tools.speed import cases as C
from silbridge.tools.speed.figures import add_campaign, add_ratios, case_figures, targets


def case_list(duration_s: float, physics_hz: float, *, imu_hz: int | None,
              arducopter: str | None, campaign: int | None = None) -> list:
    """In run order: bare JSBSim first, so every round starts from the reference."""
    out = [C.bare_jsbsim(duration_s, physics_hz)]
    for log in (False, True):
        out += [C.flight(duration_s, n, log=log) for n in (1, 2)]
    if imu_hz:
        out += [C.flight(duration_s, n, imu_hz=imu_hz) for n in (1, 2)]
    if campaign:
        out += [C.campaign(duration_s, jobs, campaign) for jobs in (1, 2)]
    if arducopter:
        out.append(C.arducopter_own_physics(arducopter, duration_s))
    return out


def physics_rate_hz() -> float:
    return float(load_scenario(C.SCENARIO).physics.rate_hz)


def measure(duration_s: float, runs: int, *, imu_hz: int | None = None,
            arducopter: str | None = None, campaign: int | None = None,
            skipped: dict | None = None,
            progress: Callable[[str], None] = lambda s: None) -> dict:
    """The `silbridge speed --json` object. skipped: {case name: why} for cases left out."""
    physics_hz = physics_rate_hz()
    todo = case_list(duration_s, physics_hz, imu_hz=imu_hz, arducopter=arducopter,
                     campaign=campaign)
    done: dict[str, list[dict]] = {c.name: [] for c in todo}
    for i in range(runs):
        for c in todo:
            r = c.run()
            done[c.name].append(r)
            progress(f"round {i + 1}/{runs}  {c.label:<40} {r['realtime_factor']:7.1f}x")
    figures = {c.name: {"label": c.label, "runs": done[c.name]} |
               case_figures(done[c.name], physics_hz) for c in todo}
    add_ratios(figures)
    add_campaign(figures)
    return {"scenario": C.SCENARIO, "physics_hz": physics_hz, "duration_s": duration_s,
            "runs": runs, "imu_hz": imu_hz, "campaign": campaign,
            "order": [c.name for c in todo],
            "cases": figures, "targets": targets(figures), "skipped": skipped or {}}
