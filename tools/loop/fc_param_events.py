"""A scenario's [[fc_param]] entries, checked against the FC's declaration and handed to it.

The bridge reads scenarios but knows no FC parameters; the FC knows its parameters but
reads no scenario (bridge/ and fc_sil/ never import each other). This glue does both
halves: at load, each entry's name and value are checked as the FC would check them, so a
typo fails before anything flies; at start, the entries become the FC's ParamSchedule,
in this process (`fly --processes 1`, the campaigns) or as `silbridge fc --param-at`
arguments (`fly --processes 2`).

A scenario's [[failure]] entries of the FC-side units (rc, gcs: the FC's own links; the
bridge's fault engine only reports them) travel the same way, as the switch parameters our FC
declares for them (fc_sil/sim_faults.py): SIM_RC_FAIL and SB_SIM_GCS_FAIL, 1 at at_s and 0 at
at_s + duration_s (none: the loss lasts to the end of the run).
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


# FC-side fault unit -> the FC parameter that switches it (fc_sil/sim_faults.py).
FC_SIDE_SWITCH = {"rc": "SIM_RC_FAIL", "gcs": "SB_SIM_GCS_FAIL"}


def param_events(sc) -> tuple[ParamEvent, ...]:
    """The scenario's parameter changes, as the FC schedules them: its [[fc_param]] entries,
    then the switches of its FC-side [[failure]] entries."""
    events = [ParamEvent(at_ns=round(p.at_s * _NS), name=lookup(p.name).name, value=p.value)
              for p in sc.fc_params]
    for f in getattr(sc, "failures", ()):
        name = FC_SIDE_SWITCH.get(f.unit)
        if name is None:
            continue
        events.append(ParamEvent(at_ns=round(f.at_s * _NS), name=name, value=1.0))
        if f.duration_s is not None:
            events.append(ParamEvent(at_ns=round((f.at_s + f.duration_s) * _NS), name=name,
                                     value=0.0))
    return tuple(events)


def param_at_args(events) -> list[str]:
    """The same changes for a `silbridge fc` subprocess."""
    args = []
    for ev in events:
        args += ["--param-at", format_param_at(ev)]
    return args
