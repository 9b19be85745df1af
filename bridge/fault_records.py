"""The FC's forwarded faults, arriving beside its PWM: FAULT records -> the fault engine.

Our FC switches faults it was asked for (MAV_CMD_INJECT_FAILURE, ArduPilot's SIM_* names;
fc_sil/fault_inject.py) and forwards each switch as a FAULT record on its output link, in the
actuator ring over shared memory, as a COMMAND_LONG over MAVLink HIL (mavlink/hil/hil_fault.py,
rebuilt into the same record). Wherever the bridge collects its PWM it hands the other records
here; each FAULT becomes ``sim.faults.inject(unit, type, instance, params, on, sim_ns)``, so
it takes effect before the next physics step.

A record the catalog cannot read (an unknown unit or type code, an instance the unit has not,
a NaN parameter) or the engine refuses is counted in ``malformed`` and dropped: what the FC
sends must never stop the physics. Records of any other kind there are counted as ``stray``.
"""

from __future__ import annotations

import logging
import math
from collections import Counter

import numpy as np

from silbridge.shm import fault_catalog as cat
from silbridge.shm.records import FAULT_DTYPE, KIND_FAULT, KIND_PWM

log = logging.getLogger(__name__)


class FaultRecords:
    """Counts and routes the non-PWM records of the actuator link (see module text)."""

    def __init__(self, sim):
        self.sim = sim
        self.received = 0
        self.malformed = 0
        self.stray = 0
        self.by_unit: Counter = Counter()     # unit name -> FAULT records read (malformed: "?")

    def route(self, recs: np.ndarray) -> None:
        """recs: records of one collection (generic view), PWM among them skipped."""
        kinds = recs["kind"]
        for i in np.flatnonzero(kinds != KIND_PWM):
            if kinds[i] != KIND_FAULT:
                self.stray += 1
                continue
            self._one(recs[i:i + 1].view(FAULT_DTYPE)[0])

    def _one(self, r) -> None:
        self.received += 1
        why = self._inject(r)
        if why is not None:
            self.malformed += 1
            log.warning("FAULT record dropped: %s", why)

    def _inject(self, r) -> str | None:
        u = cat.unit_coded(int(r["unit"]))
        t = u.type_coded(int(r["type"])) if u is not None else None
        self.by_unit[u.name if t is not None else "?"] += 1
        if t is None or int(r["action"]) not in (0, 1):
            return (f"unit {int(r['unit'])} type {int(r['type'])} action {int(r['action'])} "
                    f"is not in the fault catalog")
        slots = [float(x) for x in r["params"]]
        if not all(math.isfinite(x) for x in slots):
            return f"{u.name}.{t.name}: a parameter is not finite"
        sim = self.sim
        try:
            sim.faults.inject(u.name, t.name, int(r["instance"]), cat.unpack_params(t, slots),
                              bool(r["action"]), sim.sim_ns)
        except (RuntimeError, ValueError, TypeError) as exc:    # FaultError is a RuntimeError
            return f"{u.name}.{t.name}[{int(r['instance'])}]: {exc}"
        return None

    def counters(self) -> dict:
        return {"faults_received": self.received, "faults_malformed": self.malformed,
                "actuator_stray": self.stray}


def fault_summary(engine, records: FaultRecords) -> dict:
    """What a run's faults did, per unit, for its summary: the switches the fault engine made
    (a scenario's [[failure]] entries and the FC's forwarded faults) and the FAULT records
    (kind 11) read from the FC. Empty for a run without either, so a fault-free summary keeps
    its keys."""
    units = sorted({u for u, _ in engine.switched} | set(records.by_unit))
    if not units:
        return {}
    return {u: {"on": engine.switched[(u, "on")], "off": engine.switched[(u, "off")],
                "fault_records": records.by_unit[u]} for u in units}
