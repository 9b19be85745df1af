"""The FC's timed parameter changes: applied once, after the step that reaches their time."""

import pytest

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.param_schedule import (ParamEvent, ParamSchedule, format_param_at,
                                             parse_param_at)


class _Loop:
    def __init__(self):
        self.last_sim_ns = 0
        self.sink = _Sink()


class _Sink:
    def __init__(self):
        self.events = []

    def event(self, sim_ns, kind, text, **fields):
        self.events.append((sim_ns, kind, fields))


def test_changes_apply_at_their_step_in_order_and_are_logged():
    core, loop = FlightCore(), _Loop()
    sched = ParamSchedule(core, [ParamEvent(3_000_000, "SB_ATT_SRC", 0.0),
                                 ParamEvent(1_500_000, "SB_ATT_SRC", 1.0)])
    for step_end_ns in (1_000_000, 2_000_000, 3_000_000, 4_000_000):
        loop.last_sim_ns = step_end_ns
        sched.after_batch(loop)
        if step_end_ns == 2_000_000:
            assert core.get_param("SB_ATT_SRC") == 1
    assert core.get_param("SB_ATT_SRC") == 0
    assert sched.applied == [(2_000_000, "SB_ATT_SRC", 1.0), (3_000_000, "SB_ATT_SRC", 0.0)]
    assert [(t, k, f["value"]) for t, k, f in loop.sink.events] == [
        (2_000_000, "param", 1.0), (3_000_000, "param", 0.0)]


def test_param_at_text_round_trips_and_bad_text_says_the_form():
    ev = ParamEvent(40_000_000_000, "SB_BLEND_TC", 0.1)
    assert parse_param_at(format_param_at(ev)) == ev
    with pytest.raises(ValueError, match="NAME=VALUE@SECONDS"):
        parse_param_at("SB_ATT_SRC=1")
