"""A scenario's [[fc_param]] entries, checked against the FC's declaration and handed to it.

The bridge reads scenarios but knows no FC parameters; the FC knows its parameters but
reads no scenario (bridge/ and fc_sil/ never import each other). This glue does both
halves: at load, each entry's name and value are checked as the FC would check them, so a
typo fails before anything flies; at start, the entries become the FC's ParamSchedule,
in this process (`fly --processes 1`, the campaigns) or as `silbridge fc --param-at`
arguments (`fly --processes 2`).
"""

from __future__ import annotations

from silbridge.bridge.scenario import load_scenario
from silbridge.fc_sil.param_schedule import ParamEvent, format_param_at
from silbridge.fc_sil.params import lookup
from silbridge.shm.records import NS_PER_S as _NS


def check_fc_param(name: str, value) -> None:
    """ParamError (a ValueError) for a name the FC does not declare or a value it refuses."""
    lookup(name).validate(value)


def load_flight_scenario(name_or_path, seed: int | None = None):
    """load_scenario with its [[fc_param]] entries checked against the FC's parameters."""
    return load_scenario(name_or_path, seed=seed, check_fc_param=check_fc_param)


def param_events(sc) -> tuple[ParamEvent, ...]:
    """The scenario's parameter changes, as the FC schedules them."""
    return tuple(ParamEvent(at_ns=round(p.at_s * _NS), name=lookup(p.name).name, value=p.value)
                 for p in sc.fc_params)


def param_at_args(events) -> list[str]:
    """The same changes for a `silbridge fc` subprocess."""
    args = []
    for ev in events:
        args += ["--param-at", format_param_at(ev)]
    return args
