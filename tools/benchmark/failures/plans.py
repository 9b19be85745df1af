"""F1..F12 as the suite reads them: failures.toml's plans, checked against the fault catalog,
and the scenario each run flies (physics.toml plus the plan's [[failure]] entries).

The phase times are the same for every autopilot and every plan: the client takes off as
soon as the autopilot lets it (ArduCopter's EKF waits about 47 s of sim time for its GPS),
holds, starts the plan's phase at PHASE_AT_S and the fault hits at the plan's at_s. A
vehicle that is not flying the phase by then is reported as such, not scored.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from silbridge.shm import fault_catalog as cat

HERE = Path(__file__).parent
PLANS_TOML = HERE / "failures.toml"
PHYSICS_TOML = HERE / "physics.toml"
ALT_M = 10.0             # hold and mission height above home [m]
PHASE_AT_S = 70.0        # sim time the mission starts (hold: the hover goes on) [s]
CLIENT_UNITS = ("gcs",)  # faults the benchmark client makes itself (it stops talking)
# The mission of the "mission" phase: a square of 80 m legs (N, E metres of home), flown at
# 5 m/s (failsafe_params.py sets every autopilot's cruise speed), about 70 s.
MISSION_NE = ((80.0, 0.0), (80.0, 80.0), (0.0, 80.0), (0.0, 0.0))


@dataclass(frozen=True)
class FailurePlan:
    name: str                # F1..F12
    title: str
    phase: str               # "hold" or "mission"
    end_s: float             # sim time the run ends unless it landed and disarmed first
    failures: tuple          # dicts: the [[failure]] entries, as written in failures.toml
    physics: tuple = ()      # (key, value) of [plan.physics]: the scenario's [physics] keys

    @property
    def fault_on_s(self) -> float:
        return min(f["at_s"] for f in self.failures)

    @property
    def fault_off_s(self) -> float:
        """When the last fault ends (end_s when one lasts to the end of the run)."""
        ends = [f["at_s"] + f["duration_s"] if "duration_s" in f else math.inf
                for f in self.failures]
        return min(max(ends), self.end_s)

    @property
    def budget_s(self) -> float:
        """Sim seconds the physics may serve on top of the boot slack (nav's in_process)."""
        return self.end_s

    @property
    def units(self) -> tuple:
        return tuple(dict.fromkeys(f["unit"] for f in self.failures))

    def engine_failures(self) -> tuple:
        """The entries the bridge's fault engine applies (not the client's own)."""
        return tuple(f for f in self.failures if f["unit"] not in CLIENT_UNITS)

    def client_windows(self) -> tuple:
        """(on_s, off_s) of each fault the client makes itself (GCS loss)."""
        return tuple((f["at_s"], f["at_s"] + f.get("duration_s", math.inf))
                     for f in self.failures if f["unit"] in CLIENT_UNITS)


class PlanError(Exception):
    user_facing = True


def _check(name: str, entry: dict) -> None:
    unit = cat.unit_named(entry.get("unit", ""))
    if unit is None or unit.type_named(entry.get("type", "")) is None:
        raise PlanError(f"{PLANS_TOML}: {name}: unknown fault {entry.get('unit')}."
                        f"{entry.get('type')}: see shm/fault_catalog.py")
    if entry["at_s"] < PHASE_AT_S:
        raise PlanError(f"{PLANS_TOML}: {name}: a fault at {entry['at_s']:g} s comes before "
                        f"the phase starts ({PHASE_AT_S:g} s)")


def load_plans(path: Path = PLANS_TOML) -> dict[str, FailurePlan]:
    with open(path, "rb") as fh:
        raw = tomllib.load(fh)
    plans = {}
    for p in raw["plan"]:
        for f in p["failure"]:
            _check(p["name"], f)
        if p["phase"] not in ("hold", "mission"):
            raise PlanError(f"{path}: {p['name']}: phase is hold or mission, not {p['phase']!r}")
        plans[p["name"]] = FailurePlan(p["name"], p["title"], p["phase"], float(p["end_s"]),
                                       tuple(dict(f) for f in p["failure"]),
                                       tuple(p.get("physics", {}).items()))
    return plans


PLANS = load_plans()


def plan_names(text: str) -> list[str]:
    """--scenarios of the failures suite: F1..F12, comma-separated ("all" = every one)."""
    names = [n.strip().upper() for n in text.split(",") if n.strip()]
    if names == ["ALL"]:
        return list(PLANS)
    bad = [n for n in names if n not in PLANS]
    if not names or bad:
        from silbridge.tools.benchmark.campaign import CampaignError
        raise CampaignError(f"--suite failures flies {', '.join(PLANS)}: give --scenarios "
                            f"{','.join(PLANS)} or a part of it, not {text!r}")
    return list(dict.fromkeys(names))


def _toml_value(v) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v)


def scenario_text(plan: FailurePlan) -> str:
    """physics.toml with the plan's [physics] keys and its engine faults appended as
    [[failure]] entries."""
    parts = [PHYSICS_TOML.read_text().rstrip(), ""]
    if plan.physics:
        parts.append(f"[physics]   # {plan.name}")
        parts += [f"{k} = {_toml_value(v)}" for k, v in plan.physics]
        parts.append("")
    for f in plan.engine_failures():
        parts.append(f"[[failure]]   # {plan.name}")
        parts += [f"{k} = {_toml_value(v)}" for k, v in f.items()]
        parts.append("")
    return "\n".join(parts)


def write_scenario(plan: FailurePlan, out_dir: str) -> str:
    """The plan's scenario file in out_dir (kept beside the logs: what was flown)."""
    path = Path(out_dir) / f"scenario-{plan.name}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(scenario_text(plan))
    return str(path)


@dataclass(frozen=True)
class PlanRun:
    """A plan bound to its scenario file: what nav's runners read (physics_path, name,
    budget_s) plus the plan itself."""
    plan: FailurePlan
    physics_path: str

    @property
    def name(self) -> str:
        return self.plan.name

    @property
    def budget_s(self) -> float:
        return self.plan.budget_s
