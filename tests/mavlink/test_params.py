"""PARAM_* protocol: list, read, set, bad input, ArduPilot integer encoding, save on change."""

from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.params_file import load_parm
from silbridge.mavlink.gcs.server import ServerTiming


def _set(client, name, value, ptype=mav.MAV_PARAM_TYPE_REAL32):
    client.drain()
    client.send(mav.MAVLink_param_set_message(1, 1, name.encode(), value, ptype))


def test_request_list_streams_every_param_with_stable_indices(env):
    names = list(env.params.names())
    env.client.send(mav.MAVLink_param_request_list_message(1, 1))
    got = {}
    end = time.monotonic() + 3.0
    while len(got) < len(names) and time.monotonic() < end:
        m = env.client.wait("PARAM_VALUE", timeout_s=0.5)
        if m is not None:
            got[m.param_index] = m
    assert sorted(got) == list(range(len(names)))
    for i, m in got.items():
        assert m.param_id == names[i]
        assert m.param_count == len(names)
    # integers travel C-cast as floats, with their integer type
    mygcs = got[names.index("SYSID_MYGCS")]
    assert mygcs.param_type == mav.MAV_PARAM_TYPE_INT16 and mygcs.param_value == 255.0
    p = got[names.index("ATC_RAT_RLL_P")]
    assert p.param_type == mav.MAV_PARAM_TYPE_REAL32 and math.isclose(p.param_value, 0.135,
                                                                      rel_tol=1e-6)


def test_read_by_name_and_index_and_unknown(env):
    c = env.client
    c.send(mav.MAVLink_param_request_read_message(1, 1, b"RTL_ALT", -1))
    m = c.wait("PARAM_VALUE", lambda m: m.param_id == "RTL_ALT")
    assert m.param_value == 1500.0 and m.param_type == mav.MAV_PARAM_TYPE_INT32
    idx = m.param_index
    c.send(mav.MAVLink_param_request_read_message(1, 1, b"", idx))
    assert c.wait("PARAM_VALUE", lambda m: m.param_index == idx).param_id == "RTL_ALT"
    c.send(mav.MAVLink_param_request_read_message(1, 1, b"NO_SUCH_PARAM", -1))
    err = c.wait("PARAM_ERROR")
    assert err.param_id == "NO_SUCH_PARAM" and err.error == mav.MAV_PARAM_ERROR_DOES_NOT_EXIST
    assert (err.target_system, err.target_component) == (255, 190)
    c.send(mav.MAVLink_param_request_read_message(1, 1, b"", 999))
    assert c.wait("PARAM_ERROR", lambda m: m.param_index == 999) is not None


def test_set_takes_effect_and_is_echoed(env):
    _set(env.client, "ATC_RAT_RLL_P", 0.2)
    m = env.client.wait("PARAM_VALUE", lambda m: m.param_id == "ATC_RAT_RLL_P")
    assert math.isclose(m.param_value, 0.2, rel_tol=1e-6)
    assert math.isclose(env.params.get("ATC_RAT_RLL_P")[0], 0.2, rel_tol=1e-6)
    # integer parameter: float on the wire, rounded into the integer type
    _set(env.client, "RTL_ALT", 2000.4, mav.MAV_PARAM_TYPE_INT32)
    m = env.client.wait("PARAM_VALUE", lambda m: m.param_id == "RTL_ALT")
    assert m.param_value == 2000.0 and m.param_type == mav.MAV_PARAM_TYPE_INT32
    assert env.params.get("RTL_ALT")[0] == 2000 and isinstance(env.params.get("RTL_ALT")[0], int)


def _expect_refused(env, name, value, fragment, ptype=mav.MAV_PARAM_TYPE_REAL32):
    before = env.params.get(name)[0] if name in env.params.names() else None
    _set(env.client, name, value, ptype)
    st = env.client.wait("STATUSTEXT", lambda m: name in m.text)
    assert st is not None and fragment in st.text, st
    if before is not None:
        echo = env.client.wait("PARAM_VALUE", lambda m: m.param_id == name)
        assert echo is not None and echo.param_value == float(before) or math.isclose(
            echo.param_value, before, rel_tol=1e-6)
        assert env.params.get(name)[0] == before
    err = env.client.wait("PARAM_ERROR", lambda m: m.param_id == name)
    assert err is not None


def test_bad_sets_keep_value_and_say_why(env):
    _expect_refused(env, "NOT_A_PARAM", 1.0, "unknown parameter")
    _expect_refused(env, "ATC_RAT_RLL_P", float("nan"), "not finite")
    _expect_refused(env, "ATC_RAT_RLL_P", float("inf"), "not finite")
    _expect_refused(env, "ATC_RAT_RLL_P", 7.0, "out of range")
    _expect_refused(env, "INS_HNTCH_ENABLE", 300.0, "not in INT8 range", mav.MAV_PARAM_TYPE_INT8)
    _expect_refused(env, "SYSID_MYGCS", 0.0, "out of range", mav.MAV_PARAM_TYPE_INT16)
    c = env.server.counters()
    assert c["param_sets_refused"] == 6 and c["param_sets_ok"] == 0


def test_set_is_saved_atomically_to_param_file(make_env, tmp_path):
    path = tmp_path / "vehicle.parm"
    e = make_env(param_file=path, timing=ServerTiming(param_save_delay_s=0.05))
    _set(e.client, "WPNAV_SPEED", 750.0)
    _set(e.client, "MOT_PWM_MIN", 1100.0, mav.MAV_PARAM_TYPE_INT16)
    assert e.client.wait("PARAM_VALUE", lambda m: m.param_id == "MOT_PWM_MIN")
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        if path.exists() and "MOT_PWM_MIN" in path.read_text() \
                and dict(load_parm(path)).get("MOT_PWM_MIN") == 1100.0:
            break
        time.sleep(0.02)
    values = dict(load_parm(path))
    assert values["WPNAV_SPEED"] == 750.0 and values["MOT_PWM_MIN"] == 1100.0
    assert "MOT_PWM_MIN      1100\n" in path.read_text()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_preflight_storage_without_file_is_denied(env):
    ack = env.client.command_long(mav.MAV_CMD_PREFLIGHT_STORAGE, p1=1)
    assert ack.result == mav.MAV_RESULT_DENIED


def test_ftp_param_download_is_nakked_at_once(env):
    payload = bytearray(251)
    payload[0:2] = (7).to_bytes(2, "little")     # seq
    payload[3] = 4                               # OpenFileRO
    path = b"@PARAM/param.pck?withdefaults=1"
    payload[4] = len(path)
    payload[12:12 + len(path)] = path
    env.client.send(mav.MAVLink_file_transfer_protocol_message(0, 1, 1, list(payload)))
    m = env.client.wait("FILE_TRANSFER_PROTOCOL", timeout_s=1.0)
    assert m is not None
    p = bytes(m.payload)
    assert int.from_bytes(p[0:2], "little") == 8          # seq + 1
    assert p[3] == 129 and p[5] == 4 and p[4] == 1 and p[12] == 10   # NAK FileNotFound
    assert (m.target_system, m.target_component) == (255, 190)


def test_preflight_storage_save_and_load(make_env, tmp_path):
    path = tmp_path / "store.parm"
    e = make_env(param_file=path)
    ack = e.client.command_long(mav.MAV_CMD_PREFLIGHT_STORAGE, p1=1)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    text = path.read_text()
    assert "ANGLE_MAX        3000\n" in text
    path.write_text(text.replace("ANGLE_MAX        3000", "ANGLE_MAX 4500")
                    + "NOT_KNOWN 1\n")
    ack = e.client.command_long(mav.MAV_CMD_PREFLIGHT_STORAGE, p1=0)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert e.params.get("ANGLE_MAX")[0] == 4500
    assert e.client.wait("STATUSTEXT", lambda m: "NOT_KNOWN" in m.text) is not None


def test_load_into_store_at_start(tmp_path):
    from mavtest_vehicle import DeclaredParamStore

    from silbridge.mavlink.gcs.params_file import load_into_store
    store = DeclaredParamStore()
    assert load_into_store(tmp_path / "absent.parm", store) == []
    (tmp_path / "p.parm").write_text("RTL_ALT 2500\nATC_RAT_RLL_P 3\n")
    problems = load_into_store(tmp_path / "p.parm", store)
    assert store.get("RTL_ALT")[0] == 2500 and len(problems) == 1
