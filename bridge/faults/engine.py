"""The fault engine: the one place that knows which faults are on.

Faults come from the fault catalog (shm/fault_catalog.py) and reach the engine two ways:
the scenario's ``[[failure]]`` entries, switched here at their step, and ``inject()``, the
runtime switch the FC's forwarded fault (MAV_CMD_INJECT_FAILURE, SIM_* parameters) arrives
through. Either way the engine keeps the active set and tells the unit's applier, the
object beside what the fault changes (the sensor stage, the GNSS model, the motors, the
battery, the SIL link), through ``on(fault, sim_ns)`` / ``off(fault, sim_ns)``.

Timing, as disturbances: a scenario entry switches on before the first physics step that
starts at or after at_s and off before the first step at or after at_s + duration_s;
``next_step`` is the step of the next switch (or of an applier's timer, ``wake_at``), so a
step batch ends there. ``inject`` applies at once: called between steps, it takes effect at
the next one. A later switch of the same (unit, type, instance) replaces the earlier one
(whose scheduled end then no longer clears it).

rc and gcs are the FC's units: the engine reports them (events, ``active``) and the layer
that joins bridge and FC hands them on; any other unit needs a registered applier, and a
fault of a unit nobody registered is an error at the run's first step (or at inject),
never silently ignored.
Every switch is an event (sim_ns, text) in the simulator's event list.
"""

from __future__ import annotations

import heapq
from collections import Counter
from dataclasses import dataclass

from silbridge.bridge.disturbances import step_starting_at
from silbridge.shm import fault_catalog as cat

FC_SIDE_UNITS = ("rc", "gcs")   # applied by the FC; the engine only reports them


class FaultError(RuntimeError):
    """A fault that cannot be applied: unknown unit, type, instance or parameter, or a unit
    with no applier in this run."""

    user_facing = True


@dataclass(frozen=True)
class ActiveFault:
    unit: str
    type: str
    instance: int
    params: dict       # every parameter of the type by name (catalog defaults filled in)
    t_on_ns: int       # sim time it switched on [ns]

    @property
    def key(self) -> tuple:
        return (self.unit, self.type, self.instance)


def resolve(unit: str, ftype: str, instance: int, params: dict) -> tuple:
    """(FaultUnit, FaultType, params with defaults) of a fault, checked against the
    catalog; FaultError naming what is wrong and what is allowed."""
    u = cat.unit_named(unit)
    if u is None:
        raise FaultError(f"unknown fault unit {unit!r}; one of "
                         f"{', '.join(x.name for x in cat.UNITS)}")
    t = u.type_named(ftype)
    if t is None:
        raise FaultError(f"unknown {unit} fault type {ftype!r}; one of "
                         f"{', '.join(x.name for x in u.types)}")
    if instance not in u.instances:
        raise FaultError(f"{unit} has no instance {instance}; one of "
                         f"{', '.join(map(str, u.instances))} ({u.instance_text})")
    names = [p.name for p in t.params]
    unknown = sorted(set(params) - set(names))
    if unknown:
        raise FaultError(f"{unit}.{ftype} has no parameter {unknown[0]!r}; "
                         f"its parameters: {', '.join(names) or 'none'}")
    full = {}
    for p in t.params:
        v = params.get(p.name, p.default)
        full[p.name] = tuple(float(x) for x in v) if p.slots == 3 else (
            int(v) if p.kind == "int" else float(v))
    return u, t, full


def describe(f: ActiveFault) -> str:
    def fmt(v):
        return "[" + ", ".join(f"{x:g}" for x in v) + "]" if isinstance(v, tuple) else f"{v:g}"
    args = " ".join(f"{k}={fmt(v)}" for k, v in f.params.items())
    return f"{f.unit}.{f.type}[{f.instance}]" + (f" {args}" if args else "")


class FaultEngine:
    """failures: the scenario's [[failure]] entries (Sections: unit, type, instance, at_s,
    duration_s and the type's parameters); dt_ns the physics step; on_event(sim_ns, text)
    the simulator's event list."""

    def __init__(self, failures, dt_ns: int, duration_s: float, on_event):
        self.dt_ns = dt_ns
        self.on_event = on_event
        self._appliers: dict[str, object] = {}
        self._active: dict[tuple, ActiveFault] = {}
        self.switched: Counter = Counter()      # (unit, "on" | "off") -> switches made
        self._owner: dict[tuple, int | None] = {}   # key -> the [[failure]] that set it last
        switches = []
        for i, e in enumerate(failures):
            _, _, params = resolve(e.unit, e.type, e.instance,
                                   {k: v for k, v in e.__dict__.items() if k not in _COMMON})
            switches.append((step_starting_at(e.at_s, dt_ns), 1, i, e, params))
            end_s = e.at_s + e.duration_s if e.duration_s is not None else None
            if end_s is not None and end_s < duration_s:
                switches.append((step_starting_at(end_s, dt_ns), 0, i, e, params))
        # Off before on at the same step, then in file order: deterministic.
        self._switches = sorted(switches, key=lambda s: (s[0], s[1], s[2]))
        self._next = 0
        self._timers: list = []     # heap of (step, order, callback)
        self._timer_order = 0
        self._checked = not self._switches
        self.pollers: list = []     # appliers that follow the simulation (poll(sim_ns))
        self.next_step = -1
        self._update_next()

    # --- what other parts call ----------------------------------------------------------
    def register(self, unit: str, applier) -> None:
        """The applier of a unit: on(fault, sim_ns) and off(fault, sim_ns) are called after
        the active set changed (active(unit) already shows the change)."""
        if cat.unit_named(unit) is None:
            raise FaultError(f"cannot register an applier for unknown unit {unit!r}")
        if unit in self._appliers:
            raise FaultError(f"fault unit {unit!r} already has an applier")
        self._appliers[unit] = applier

    def handles(self, unit: str) -> bool:
        """True when a fault of this unit can be applied in this run."""
        return unit in self._appliers or unit in FC_SIDE_UNITS

    def active(self, unit: str) -> list[ActiveFault]:
        """The unit's active faults, in the order they switched on."""
        return [f for f in self._active.values() if f.unit == unit]

    def all_active(self) -> list[ActiveFault]:
        return list(self._active.values())

    def inject(self, unit: str, type: str, instance: int, params: dict, on: bool,
               sim_ns: int) -> None:
        """Switch a fault now (between steps: it takes effect at the next step). on=False
        clears that (unit, type, instance); clearing one that is not on only reports."""
        _, _, full = resolve(unit, type, int(instance), dict(params or {}))
        self._require_applier(unit)
        fault = ActiveFault(unit, type, int(instance), full, int(sim_ns))
        self._set(fault, on, sim_ns, "inject")
        self._owner[fault.key] = None

    def wake_at(self, step: int, callback) -> None:
        """Call callback(step) before physics step `step` (an applier's own timing, e.g. an
        ESC dropout); the batch ends there like at a switch."""
        self._timer_order += 1
        heapq.heappush(self._timers, (int(step), self._timer_order, callback))
        self._update_next()

    def set_poll(self, applier, polling: bool) -> None:
        """While polling, applier.poll(sim_ns) is called on the steps the simulator's Python
        sees (at least every GNSS epoch): for a fault that follows a slow quantity."""
        if polling and applier not in self.pollers:
            self.pollers.append(applier)
        elif not polling and applier in self.pollers:
            self.pollers.remove(applier)

    # --- the simulator's hooks -----------------------------------------------------------
    def poll(self, sim_ns: int) -> None:
        for applier in list(self.pollers):
            applier.poll(sim_ns)

    def switch(self, k: int) -> None:
        """The switches and timers due before step k (call when k == next_step)."""
        if not self._checked:
            self._checked = True
            for _, _, i, e, _ in self._switches:
                self._require_applier(e.unit, f"failure[{i}]: ")
        sim_ns = (k - 1) * self.dt_ns
        sw = self._switches
        while self._next < len(sw) and sw[self._next][0] == k:
            _, on, i, e, params = sw[self._next]
            self._next += 1
            fault = ActiveFault(e.unit, e.type, e.instance, params, sim_ns)
            if not on and self._owner.get(fault.key) != i:
                continue    # replaced meanwhile by a later switch of the same fault
            self._set(fault, bool(on), sim_ns, f"failure[{i}]")
            self._owner[fault.key] = i
        timers = self._timers
        while timers and timers[0][0] <= k:
            _, _, callback = heapq.heappop(timers)
            callback(k)
        self._update_next()

    # --- inside ----------------------------------------------------------------------------
    def _require_applier(self, unit: str, where: str = "") -> None:
        if not self.handles(unit):
            known = ", ".join(sorted(self._appliers) + list(FC_SIDE_UNITS))
            raise FaultError(f"{where}no part of this run applies {unit} faults (units with an "
                             f"applier: {known}); remove the failure or run with the part that "
                             f"models the {unit}")

    def _set(self, fault: ActiveFault, on: bool, sim_ns: int, source: str) -> None:
        old = self._active.pop(fault.key, None)
        applier = self._appliers.get(fault.unit)
        if old is not None and applier is not None:
            applier.off(old, sim_ns)
        if on:
            self._active[fault.key] = fault
            if applier is not None:
                try:
                    applier.on(fault, sim_ns)
                except Exception:   # refused (FaultError): it is not on
                    self._active.pop(fault.key, None)
                    raise
        state = "on" if on else ("off" if old is not None else "off (was not on)")
        if on or old is not None:
            self.switched[(fault.unit, "on" if on else "off")] += 1
        self.on_event(sim_ns, f"{source} {state}: {describe(fault if on else (old or fault))}")

    def _update_next(self) -> None:
        due = []
        if self._next < len(self._switches):
            due.append(self._switches[self._next][0])
        if self._timers:
            due.append(self._timers[0][0])
        if not self._checked:
            due.append(1)
        self.next_step = min(due) if due else -1


_COMMON = ("unit", "type", "instance", "at_s", "duration_s")
