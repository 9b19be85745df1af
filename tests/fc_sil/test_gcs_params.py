"""The published ground-station parameter list (docs/gcs_params.txt): every parameter
QGroundControl and MAVProxy read from an ArduCopter is declared, with ArduCopter 4.6.0's type,
in the 1000-2999 block or before; docs/params.md says for each whether it acts in SIL."""

from __future__ import annotations

from silbridge.fc_sil import params as P
from silbridge.tools.param_effects import NO_EFFECT, effect, gcs_param_types, where_acts



def test_every_listed_parameter_is_declared_with_arducopters_type():
    listed = gcs_param_types()
    assert len(listed) >= 220
    missing = [n for n in listed if n not in P.BY_NAME]
    assert not missing
    wrong = [(n, P.BY_NAME[n].type, t) for n, (t, _) in listed.items()
             if n in P.BY_NAME and P.BY_NAME[n].type != t]
    assert not wrong
    for n, (_, sources) in listed.items():
        assert sources and all(s.split(":")[0] in ("qgc", "mavproxy", "brief") for s in sources)


def test_ground_station_block_uses_its_own_index_range():
    gcs = [p for p in P.PARAMS if 1000 <= p.index <= 2999]
    assert len(gcs) > 180
    assert all(p.host for p in gcs)


def test_parameters_the_simulator_models_act_and_the_rest_say_so():
    fx = {p.name: effect(p) for p in P.PARAMS}
    for name in ("RC1_MIN", "RC16_REVERSED", "RC3_DZ", "RCMAP_THROTTLE", "FLTMODE1", "FLTMODE6",
                 "FLTMODE_CH", "FS_THR_ENABLE", "FS_THR_VALUE", "BATT_ARM_VOLT", "BATT_LOW_VOLT",
                 "FS_GCS_ENABLE", "RTL_ALT", "LAND_SPEED", "ARMING_CHECK"):
        assert fx[name].startswith("acts"), (name, fx[name])
    assert where_acts(P.BY_NAME["ATC_RAT_RLL_P"]) == ["C core"]
    for name in ("BATT_VOLT_PIN", "COMPASS_ORIENT", "SERVO3_MAX", "TUNE", "INS_ACC_ID"):
        assert fx[name] == NO_EFFECT, (name, fx[name])


def test_rc_calibration_defaults_are_arducopter_sitls():
    d = P.defaults()
    # copter.parm's calibrated sticks (QGC's radio page counts 1100/1900/1500 as uncalibrated)
    assert all((d[f"RC{c}_MIN"], d[f"RC{c}_MAX"], d[f"RC{c}_TRIM"]) == (1000, 2000, 1500)
               for c in range(1, 9))
    assert all((d[f"RC{c}_MIN"], d[f"RC{c}_MAX"]) == (1100, 1900) for c in range(9, 17))
    assert (d["RC1_DZ"], d["RC3_DZ"], d["FLTMODE_CH"], d["FS_THR_VALUE"]) == (20, 30, 5, 975)
