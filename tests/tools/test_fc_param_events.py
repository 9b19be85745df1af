"""A scenario's [[fc_param]] changes reach the FC at their sim time, in 1 and 2 processes."""

from __future__ import annotations

import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.tools.logs.mcap_log import read_log
from silbridge.tools.loop.fc_param_events import load_flight_scenario
from silbridge.tools.loop.flight import FlightOptions, fly_one_process, fly_two_processes

BODY = 'name = "P"\nseed = 5\nduration_s = 4.0\n'
SWITCH = '[[fc_param]]\nname = "{name}"\nvalue = {value}\nat_s = {at}\n'


def _scenario(tmp_path, name="SB_ATT_SRC", value=1, at=2.5):
    path = tmp_path / "p.toml"
    path.write_text(BODY + SWITCH.format(name=name, value=value, at=at))
    return str(path)


@pytest.mark.parametrize("name, value, words", [
    ("SB_ATT_SCR", 1, ["fc_param[0]", "unknown parameter", "SB_ATT_SRC"]),
    ("SB_ATT_SRC", 2, ["fc_param[0]", "outside [0, 1]"]),
    ("SB_ATT_SRC", 0.5, ["fc_param[0]", "integer"]),
])
def test_bad_name_or_value_is_refused_at_load(tmp_path, name, value, words):
    with pytest.raises(ScenarioError) as info:
        load_flight_scenario(_scenario(tmp_path, name, value))
    for w in words:
        assert w in str(info.value), str(info.value)


@pytest.mark.parametrize("processes", [1, 2])
def test_the_change_applies_at_its_sim_time_and_is_logged(tmp_path, processes):
    fly = fly_one_process if processes == 1 else fly_two_processes
    log_path = tmp_path / f"run{processes}.mcap"
    opts = FlightOptions(scenario=_scenario(tmp_path), processes=processes,
                         log_path=str(log_path), viz_hz=0,
                         instance=f"fcparam-{processes}-{tmp_path.name}"[:40])
    fly(opts, out=lambda line: None)
    log = read_log(log_path)
    params = [e for e in log.events if e["kind"] == "param"]
    assert [(e["sim_ns"], e["fields"]["name"], e["fields"]["value"]) for e in params] == [
        (2_500_000_000, "SB_ATT_SRC", 1.0)]
    # The source weight moves towards truth only after the switch.
    st = log.channels["/fc/status"]
    assert st["blend_w"][st["sim_ns"] <= 2_500_000_000].max() == 0
    assert st["blend_w"][-1] > 0.9


def test_same_trace_in_one_and_two_processes(tmp_path):
    def opts(p):
        return FlightOptions(scenario=_scenario(tmp_path), processes=p,
                             instance=f"fcparam-h{p}-{tmp_path.name}"[:40])
    a = fly_one_process(opts(1), out=lambda line: None)
    b = fly_one_process(opts(1), out=lambda line: None)
    c = fly_two_processes(opts(2), out=lambda line: None)
    assert a["trace_hash"] == b["trace_hash"] == c["trace_hash"]
