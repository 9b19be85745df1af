"""ArduPilot's SIM_* names on our FC (fc_sil/sim_faults.py) and MAV_CMD_INJECT_FAILURE's table
(fc_sil/fault_map.py): the catalog faults they switch, in the catalog's units."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil import fault_map, sim_faults
from silbridge.fc_sil import params as P
from silbridge.fc_sil.fault_inject import FaultInjector
from silbridge.shm import fault_catalog as cat


def _get(values: dict):
    return lambda name: values.get(name, P.BY_NAME[name].default)


def _switches(inj: FaultInjector) -> list:
    recs = inj.take_outbox()
    if recs is None:
        return []
    out = []
    for r in recs:
        u = cat.unit_coded(int(r["unit"]))
        t = u.type_coded(int(r["type"]))
        out.append((u.name, t.name, int(r["instance"]), int(r["action"]),
                    cat.unpack_params(t, r["params"])))
    return out


def test_every_sim_name_is_declared_with_its_arducopter_default_and_defaults_mean_no_fault():
    for name in sim_faults.NAMES:
        assert name in P.BY_NAME, name
        assert 460 <= P.BY_NAME[name].index <= 489
    assert sim_faults.wanted(_get({}), 47.0) == {}
    d = P.defaults()      # ArduCopter 4.6.0 SITL's values, read from the real binary
    assert (d["SIM_GPS_NUMSATS"], d["SIM_ENGINE_MUL"], d["SIM_GPS_DISABLE"]) == (10, 1, 0)
    assert (P.BY_NAME["SIM_GPS_NUMSATS"].type, P.BY_NAME["SIM_ENGINE_FAIL"].type) == \
        ("INT8", "INT8")


def test_gps_glitch_degrees_become_metres_at_the_fix_latitude():
    want = sim_faults.wanted(_get({"SIM_GPS_GLITCH_X": 1e-4, "SIM_GPS_GLITCH_Y": 1e-4,
                                   "SIM_GPS_GLITCH_Z": 2.0}), 60.0)
    n, e, d = want[("gnss", "glitch", 1)]["offset_m"]
    assert n == pytest.approx(11.1319, abs=1e-3)
    assert e == pytest.approx(n * 0.5, rel=1e-9)          # cos 60 deg
    assert d == -2.0                                      # Z is up, the catalog's is down


def test_engine_failure_follows_mul_and_the_servo_and_clears_at_default():
    inj = FaultInjector(links=None)
    values = {"SIM_ENGINE_FAIL": 2, "SIM_ENGINE_MUL": 0.5}
    inj.sync_sim_params(_get(values), 0.0)
    assert _switches(inj) == [("motor", "thrust_loss", 3, 1, {"remaining": 0.5})]
    values["SIM_ENGINE_FAIL"] = 0                      # another motor: old off, new on
    inj.sync_sim_params(_get(values), 0.0)
    assert _switches(inj) == [("motor", "thrust_loss", 3, 0, {"remaining": 0.5}),
                              ("motor", "thrust_loss", 1, 1, {"remaining": 0.5})]
    values["SIM_ENGINE_MUL"] = 1.0
    inj.sync_sim_params(_get(values), 0.0)
    assert [s[:4] for s in _switches(inj)] == [("motor", "thrust_loss", 1, 0)]
    inj.sync_sim_params(_get(values), 0.0)
    assert _switches(inj) == []                          # nothing changed: nothing sent


@pytest.mark.parametrize("values, key, params", [
    ({"SIM_GPS_DISABLE": 1}, ("gnss", "off", 1), {}),
    ({"SIM_GPS_NUMSATS": 4}, ("gnss", "sats_drop", 1), {"satellites": 4, "ramp_s": 0.0}),
    ({"SIM_GPS_VERR_Y": 2.0}, ("gnss", "vel_error", 1), {"error_m_s": (0.0, 2.0, 0.0)}),
    ({"SIM_BARO_DRIFT": -0.5}, ("baro", "drift", 1), {"rate_m_s": -0.5}),
    ({"SIM_BARO_GLITCH": 15.0}, ("baro", "glitch", 1), {"offset_m": 15.0}),
    ({"SIM_BARO_FREEZE": 1}, ("baro", "stuck", 1), {}),
    ({"SIM_MAG1_FAIL": 1}, ("mag", "off", 1), {}),
    ({"SIM_MAG_MOT_Z": 20.0}, ("mag", "motor_interference", 1),
     {"gauss_per_a": (0.0, 0.0, 0.02)}),
    ({"SIM_GYR_FAIL_MSK": 1}, ("gyro", "stuck", 1), {"axis": 0}),
    ({"SIM_ACC_FAIL_MSK": 6}, None, None),               # IMUs 2 and 3: we have one
    ({"SIM_GYR1_BIAS_X": 0.1}, ("gyro", "bias", 1), {"bias": (0.1, 0.0, 0.0)}),
    ({"SIM_ACC1_BIAS_Z": 0.3}, ("accel", "bias", 1), {"bias": (0.0, 0.0, 0.3)}),
    ({"SIM_RC_FAIL": 1}, ("rc", "lost", 1), {}),
    ({"SB_SIM_GCS_FAIL": 1}, ("gcs", "lost", 1), {}),
])
def test_each_sim_parameter_asks_for_its_catalog_fault(values, key, params):
    want = sim_faults.wanted(_get(values), 0.0)
    if key is None:
        assert want == {}
        return
    assert list(want) == [key]
    got = want[key]
    assert got.keys() == params.keys()
    for k, v in params.items():
        assert got[k] == pytest.approx(v), k
    ftype = cat.unit_named(key[0]).type_named(key[1])
    assert set(got) <= {p.name for p in ftype.params}


def test_inject_failure_table_is_in_the_catalog_and_answers_as_px4():
    # every row names a catalog fault; FAILURE_TYPE_OK clears; unknowns are UNSUPPORTED
    for (u, t), m in fault_map.TABLE.items():
        inj = fault_map.from_mavlink(u, t, 0)
        assert (inj.unit, inj.type) == (m.unit, m.type)
    assert fault_map.from_mavlink(mav.FAILURE_UNIT_SYSTEM_MOTOR, mav.FAILURE_TYPE_OFF, 2).params \
        == {"remaining": 0.0}
    assert fault_map.from_mavlink(mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_TYPE_OK, 0).type is None
    for args in ((mav.FAILURE_UNIT_SENSOR_VIO, mav.FAILURE_TYPE_OFF, 0),
                 (mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_TYPE_DELAYED, 0),
                 (mav.FAILURE_UNIT_SENSOR_MAG, mav.FAILURE_TYPE_OFF, 2),
                 (mav.FAILURE_UNIT_SYSTEM_MOTOR, mav.FAILURE_TYPE_OFF, 5),
                 (250, mav.FAILURE_TYPE_OFF, 0)):
        assert isinstance(fault_map.from_mavlink(*args), str), args
    inj = FaultInjector(links=None)
    assert inj.inject_failure(mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_TYPE_OFF, 0,
                              enabled=False, gcs_loss_s=30.0)[0] == mav.MAV_RESULT_DENIED
    assert inj.take_outbox() is None
    assert inj.inject_failure(mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_TYPE_OFF, 0,
                              enabled=True, gcs_loss_s=30.0) == (mav.MAV_RESULT_ACCEPTED, None)
    assert inj.inject_failure(mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_TYPE_OK, 0,
                              enabled=True, gcs_loss_s=30.0)[0] == mav.MAV_RESULT_ACCEPTED
    assert [s[:4] for s in _switches(inj)] == [("gnss", "off", 1, 1), ("gnss", "off", 1, 0)]
