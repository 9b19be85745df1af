"""[[fc_param]] entries: shape checked by the bridge, name and value by the caller's hook."""

import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario, scenario_from_dict

GOOD = {"name": "T", "seed": 3, "duration_s": 20.0}


def _with(*entries, check=None):
    return scenario_from_dict({**GOOD, "fc_param": list(entries)}, source="t.toml",
                              check_fc_param=check)


def test_entries_load_in_order_and_reach_to_dict():
    sc = _with({"name": "SB_ATT_SRC", "value": 1, "at_s": 4.0},
               {"name": "SB_ATT_SRC", "value": 0, "at_s": 8.5})
    assert [(p.name, p.value, p.at_s) for p in sc.fc_params] == [
        ("SB_ATT_SRC", 1.0, 4.0), ("SB_ATT_SRC", 0.0, 8.5)]
    assert sc.to_dict()["fc_params"][1] == {"name": "SB_ATT_SRC", "value": 0.0, "at_s": 8.5}
    assert load_scenario("S1").fc_params == []


@pytest.mark.parametrize("entry, words", [
    ({"value": 1, "at_s": 1.0}, ["fc_param[0].name", "missing"]),
    ({"name": "X", "value": "one", "at_s": 1.0}, ["fc_param[0].value", "number"]),
    ({"name": "X", "value": 1, "at_s": -1.0}, ["fc_param[0].at_s", ">= 0"]),
    ({"name": "X", "value": 1, "at_s": 20.0}, ["fc_param[0].at_s", "end of the run"]),
    ({"name": "X", "value": 1, "at_s": 1.0, "when": 2}, ["fc_param[0].when", "unknown key"]),
])
def test_bad_entries_are_refused_naming_the_key(entry, words):
    with pytest.raises(ScenarioError) as info:
        _with(entry)
    for w in words:
        assert w in str(info.value), str(info.value)


def test_the_hook_judges_name_and_value():
    def check(name, value):
        if name != "SB_ATT_SRC":
            raise ValueError(f"unknown parameter {name!r}")
    _with({"name": "SB_ATT_SRC", "value": 1, "at_s": 1.0}, check=check)
    with pytest.raises(ScenarioError, match=r"t.toml: fc_param\[0\]: unknown parameter 'NOPE'"):
        _with({"name": "NOPE", "value": 1, "at_s": 1.0}, check=check)
