"""[[failure]] in a scenario file (bridge/scenario.py failure_entry, scenario_schema.py
FAILURE_*, bridge/faults/failure_checks.py): the keys are the fault catalog's, a wrong key,
unit, type, instance or value is a ScenarioError that names it and lists what is allowed,
and values may be drawn like [[disturbance]] keys.
"""

from __future__ import annotations

import pytest

from silbridge.bridge import scenario_schema as S
from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import load_scenario, scenario_from_dict
from silbridge.shm import fault_catalog

BASE = {"name": "t", "seed": 3, "duration_s": 10.0}


def _load(*failures, **top):
    return scenario_from_dict({**BASE, **top, "failure": list(failures)})


def test_the_schema_is_the_catalog():
    for u in fault_catalog.UNITS:
        for t in u.types:
            fields = S.FAILURE_TYPES[u.name][t.name]
            assert list(fields) == [p.name for p in t.params]
            for p in t.params:
                assert (fields[p.name].default, fields[p.name].unit) == (p.default, p.unit)


def test_a_failure_resolves_with_defaults_and_draws(tmp_path):
    path = tmp_path / "f.toml"
    path.write_text('name = "f"\nseed = 4\nduration_s = 10.0\n'
                    '[[failure]]\nunit = "motor"\ntype = "thrust_loss"\ninstance = 0\n'
                    'at_s = {uniform = [2.0, 4.0]}\nremaining = {choice = [0.25, 0.5]}\n')
    (f,) = load_scenario(path).failures
    assert (f.unit, f.type, f.instance, f.duration_s) == ("motor", "thrust_loss", 0, None)
    assert 2.0 <= f.at_s <= 4.0 and f.remaining in (0.25, 0.5)
    (g,) = _load({"unit": "gnss", "type": "glitch", "at_s": 1.0}).failures
    assert (g.instance, g.offset_m) == (1, (20.0, 0.0, 0.0))
    assert load_scenario(path).to_dict()["failures"][0]["remaining"] == f.remaining


@pytest.mark.parametrize("entry, key, words", [
    ({"unit": "gnss", "type": "glitch", "at_s": 1.0, "offset": [1, 2, 3]},
     "failure[0].offset", ["gnss.glitch", "offset_m", "at_s"]),
    ({"unit": "compass", "type": "off", "at_s": 1.0}, "failure[0].unit", ["'compass'", "mag"]),
    ({"type": "off", "at_s": 1.0}, "failure[0].unit", ["missing", "gnss"]),
    ({"unit": "baro", "type": "wobble", "at_s": 1.0}, "failure[0].type",
     ["'wobble'", "drift, stuck, glitch"]),
    ({"unit": "gyro", "type": "bias", "instance": 2, "at_s": 1.0}, "failure[0].instance",
     ["no instance 2", "0, 1"]),
    ({"unit": "motor", "type": "desync", "instance": 5, "at_s": 1.0}, "failure[0].instance",
     ["0, 1, 2, 3, 4"]),
    ({"unit": "motor", "type": "thrust_loss", "at_s": 1.0, "remaining": 1.5},
     "failure[0].remaining", ["<= 1"]),
    ({"unit": "gnss", "type": "off"}, "failure[0].at_s", ["missing required"]),
    ({"unit": "gnss", "type": "off", "at_s": 12.0}, "failure[0].at_s", ["not before the end"]),
    ({"unit": "gnss", "type": "sats_drop", "at_s": 1.0, "satellites": 4.5},
     "failure[0].satellites", ["integer"]),
])
def test_a_wrong_failure_is_a_scenario_error_naming_it(entry, key, words):
    with pytest.raises(ScenarioError) as err:
        _load(entry)
    msg = str(err.value)
    assert f"{key}:" in msg and all(w in msg for w in words), msg


def test_a_damaged_props_vibration_needs_the_vibrating_world():
    prop = {"unit": "motor", "type": "damaged_prop", "at_s": 1.0}
    with pytest.raises(ScenarioError, match=r"failure\[0\]\.imbalance_scale: .*\[vibration\] "
                                            r"enabled = true, or imbalance_scale = 1"):
        _load(prop)
    assert _load({**prop, "imbalance_scale": 1.0}).failures[0].remaining == 0.85
    assert _load(prop, vibration={"enabled": True}).failures[0].imbalance_scale == 5.0


def test_imu_failures_need_one_sample_per_step():
    with pytest.raises(ScenarioError, match=r"failure\[0\]\.unit: accel .*imu\.rate_hz"):
        _load({"unit": "accel", "type": "stuck", "at_s": 1.0}, imu={"rate_hz": 4000})
