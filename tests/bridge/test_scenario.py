"""Scenario files: built-ins load, bad files are refused with a message naming the key."""

import json

import pytest

from silbridge.bridge.errors import ScenarioError
from silbridge.bridge.scenario import builtin_names, load_scenario, scenario_from_dict

GOOD = {"name": "T", "seed": 3, "duration_s": 20.0}


def refuse(raw, *words):
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(raw, source="t.toml")
    msg = str(info.value)
    for w in words:
        assert w in msg, msg
    assert info.value.user_facing is True
    return msg


def test_builtins_load_with_paper_protocol():
    assert {"S1", "S2", "S3", "S4", "S5"} <= set(builtin_names())
    for name in ("S1", "S2", "S3", "S4", "S5"):
        sc = load_scenario(name)
        assert sc.name == name
        assert sc.duration_s == 120.0
        assert sc.windows.warmup_s == 10.0 and sc.windows.transient_end_s == 30.0
        assert sc.takeoff_alt_m == 10.0
        assert sc.imu_hz == 1000 and sc.physics_hz == 1000
        json.dumps(sc.to_dict())  # loggable


def test_drawn_values_are_in_the_paper_ranges_and_follow_the_seed():
    for seed in range(5):
        s2 = load_scenario("S2", seed=seed)
        for d in s2.disturbances:
            assert 0.02 <= d.amplitude_rad_s <= 0.05 and d.sign in (-1.0, 1.0)
        d3 = load_scenario("S3", seed=seed).disturbances[0]
        assert 0.3 <= d3.amplitude_g <= 0.8 and 0.5 <= d3.frequency_hz <= 2.0
        for sp in load_scenario("S4", seed=seed).setpoints:
            assert all(20.0 <= a <= 35.0 for a in sp.amplitude_deg)
    a, b = load_scenario("S3", seed=1), load_scenario("S3", seed=1)
    assert a.draws == b.draws
    assert load_scenario("S3", seed=2).draws != a.draws


def test_unknown_key_is_named():
    refuse({**GOOD, "durration_s": 3}, "durration_s", "unknown key")
    refuse({**GOOD, "imu": {"rte_hz": 100}}, "imu.rte_hz", "unknown key", "rate_hz")
    refuse({**GOOD, "disturbance": [{"type": "force", "start_s": 1, "amplitude_g": 0.5,
                                     "freq_hz": 1}]}, "disturbance[0].freq_hz", "unknown key")


def test_negative_rate_is_named():
    refuse({**GOOD, "imu": {"rate_hz": -1000}}, "imu.rate_hz", "> 0", "-1000")
    refuse({**GOOD, "baro": {"rate_hz": -5.0}}, "baro.rate_hz", "> 0")
    refuse({**GOOD, "gnss": {"rate_hz": 0}}, "gnss.rate_hz")


def test_missing_field_is_named():
    refuse({"name": "T", "duration_s": 5.0}, "seed", "missing")
    refuse({"name": "T", "seed": 1}, "duration_s", "missing")
    refuse({**GOOD, "disturbance": [{"type": "force", "start_s": 1.0}]},
           "disturbance[0].amplitude_g", "missing")
    refuse({**GOOD, "disturbance": [{"amplitude_g": 0.5, "start_s": 1.0}]},
           "disturbance[0].type", "missing")
    refuse({**GOOD, "setpoint": [{"type": "tilt", "start_s": 1.0}]},
           "setpoint[0].amplitude_deg", "missing")


def test_bad_values_are_named():
    refuse({**GOOD, "imu": {"rate_hz": "fast"}}, "imu.rate_hz", "number")
    refuse({**GOOD, "disturbance": [{"type": "quake", "start_s": 1}]}, "quake", "unknown type")
    refuse({**GOOD, "disturbance": [{"type": "force", "start_s": 1, "amplitude_g": {"gauss": [1, 2]}}]},
           "disturbance[0].amplitude_g", "uniform")
    refuse({**GOOD, "disturbance": [{"type": "force", "start_s": 30, "amplitude_g": 0.5}]},
           "disturbance[0].start_s", "end of the run")
    refuse({**GOOD, "physics": {"rate_hz": 3000}}, "physics.rate_hz")
    refuse({**GOOD, "seed": -1}, "seed", ">= 0")


def test_file_errors_name_the_file(tmp_path):
    p = tmp_path / "mine.toml"
    p.write_text('name = "x"\nseed = 1\nduration_s = 10\n[imu]\nrate_hz = -8\n')
    with pytest.raises(ScenarioError, match=r"mine.toml: imu.rate_hz"):
        load_scenario(p)
    with pytest.raises(ScenarioError, match="built-ins"):
        load_scenario("S9")
    p.write_text("name = \n")
    with pytest.raises(ScenarioError, match="TOML"):
        load_scenario(p)


def test_overrides_and_seed():
    sc = load_scenario("S3", seed=42, overrides={"imu.rate_hz": 8000,
                                                 "disturbance[0].frequency_hz": 1.5})
    assert sc.seed == 42 and sc.imu_hz == 8000
    assert sc.disturbances[0].frequency_hz == 1.5
    with pytest.raises(ScenarioError, match="imu.rate_hz"):
        load_scenario("S1", overrides={"imu.rate_hz": -1})


def test_the_earth_field_is_the_wmms_at_home_unless_declared():
    # Undeclared: WMM2025 at the home (through the grid the FC's COMPASS_AUTODEC reads).
    # Declinations from pygeomag 1.1.0, WMM_2025.COF, 2026.0: Zurich 3.55, Canberra 12.67 deg.
    import math

    def declination_deg(sc):
        n, e, _ = sc.mag.field_ned_gauss
        return math.degrees(math.atan2(e, n))

    zurich = scenario_from_dict(GOOD)
    assert declination_deg(zurich) == pytest.approx(3.55, abs=0.25)
    assert zurich.mag.field_ned_gauss[2] > 0                      # northern: dips down
    canberra = scenario_from_dict({**GOOD, "home": {"lat_deg": -35.363261,
                                                    "lon_deg": 149.16523}})
    assert declination_deg(canberra) == pytest.approx(12.67, abs=0.25)
    assert canberra.mag.field_ned_gauss[2] < 0
    declared = scenario_from_dict({**GOOD, "mag": {"field_ned_gauss": [0.2, 0.0, 0.4]}})
    assert declared.mag.field_ned_gauss == (0.2, 0.0, 0.4)
    assert json.dumps(zurich.to_dict())          # the run log records the field it used
