"""A ground station's parameter work against the running vehicle (`silbridge fly`, pymavlink
over UDP): the full PARAM_REQUEST_LIST with every parameter of the published ground-station
list (docs/gcs_params.txt) at ArduCopter's type and values that show QGroundControl's setup
pages as done; then RC parameters acting: RC calibration (RC3_MIN) decides the arming throttle
check, and FLTMODE_CH / FLTMODE1..6 switch modes from RC_CHANNELS_OVERRIDE."""

from __future__ import annotations

import os
import sys
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port, gcs_for, wait_for  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402
from silbridge.fc_sil.params import MAV_PARAM_TYPE  # noqa: E402
from silbridge.tools.param_effects import gcs_param_types  # noqa: E402

NO = 65535


def _param_list(c, timeout_s=60.0):
    """PARAM_REQUEST_LIST: {name: msg} once every index arrived; (values, seconds)."""
    c.drain()
    t0 = time.monotonic()
    c.send(mav.MAVLink_param_request_list_message(1, 1))
    got, count = {}, None
    while time.monotonic() - t0 < timeout_s:
        for m in c.pump(0.1):
            if m.get_type() == "PARAM_VALUE":
                count = m.param_count
                got[m.param_index] = m
        if count is not None and len(got) == count:
            return got, time.monotonic() - t0
    raise AssertionError(f"PARAM_REQUEST_LIST: {len(got)} of {count} after {timeout_s} s")


def _set(c, name, value, ptype):
    c.send(mav.MAVLink_param_set_message(1, 1, name.encode(), float(value), ptype))
    pv = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == name, timeout_s=5)
    assert pv is not None and pv.param_value == value, (name, pv)


def _with_rc(c, chans, mtype, cond, timeout_s=20.0, send=None):
    """Keep RC override (and our heartbeat) going every 0.2 s until mtype matches (only
    messages that arrive from now on count)."""
    c.drain()
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        c.send(mav.MAVLink_rc_channels_override_message(1, 1, *chans))
        c.send(c.mav.heartbeat_encode(6, 8, 0, 0, 0, 4))
        if send is not None:
            send()
        m = c.wait(mtype, cond, 0.2)
        if m is not None:
            return m
    return None


def _rc(ch3=NO, ch8=NO):
    chans = [NO] * 18
    chans[2], chans[7] = ch3, ch8
    return chans


@pytest.fixture(scope="module")
def vehicle():
    port = free_udp_port()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=4.0, processes=1)
    c = gcs_for(port)
    try:
        assert wait_for(c, "HEARTBEAT", timeout_s=60) is not None, v.stop()[-3000:]
        yield v, c
    finally:
        c.close()
        v.stop()


def test_param_list_streams_every_gcs_parameter_with_its_arducopter_type(vehicle):
    v, c = vehicle
    got, secs = _param_list(c)
    print(f"PARAM_REQUEST_LIST: {len(got)} parameters in {secs:.2f} s")
    assert sorted(got) == list(range(len(P.PARAMS)))
    assert [got[i].param_id for i in range(len(got))] == [p.name for p in P.PARAMS]
    by_name = {m.param_id: m for m in got.values()}
    missing, wrong = [], []
    for name, (typ, _) in gcs_param_types().items():
        if name not in by_name:
            missing.append(name)
        elif by_name[name].param_type != MAV_PARAM_TYPE[typ]:
            wrong.append((name, by_name[name].param_type, typ))
    assert not missing and not wrong, (missing, wrong)
    val = {n: m.param_value for n, m in by_name.items()}
    # QGroundControl's "setup complete" rules (APMAirframe/Power/Sensors/RadioComponent.cc)
    assert val["FRAME_CLASS"] != 0
    assert val["BATT_MONITOR"] != 0 and val["BATT_CAPACITY"] != 0
    for i in ("", "2", "3"):
        if val[f"COMPASS_DEV_ID{i}"] and val[f"COMPASS_USE{i}"]:
            assert all(val[f"COMPASS_OFS{i}_{a}"] != 0 for a in "XYZ")
    assert any(val[f"INS_ACCOFFS_{a}"] != 0 for a in "XYZ")
    for f in ("ROLL", "PITCH", "YAW", "THROTTLE"):
        ch = int(val[f"RCMAP_{f}"])
        assert ch > 0
        assert (val[f"RC{ch}_MIN"], val[f"RC{ch}_MAX"], val[f"RC{ch}_TRIM"]) != (1100, 1900, 1500)
    assert secs < 30.0


def test_rc_calibration_decides_the_arming_throttle_check(vehicle):
    v, c = vehicle
    bit = mav.MAV_SYS_STATUS_PREARM_CHECK
    assert wait_for(c, "SYS_STATUS", lambda m: m.onboard_control_sensors_health & bit,
                    timeout_s=60) is not None, "pre-arm checks never passed"
    arm = mav.MAV_CMD_COMPONENT_ARM_DISARM

    def send_arm():
        c.send(mav.MAVLink_command_long_message(1, 1, arm, 0, 1, 0, 0, 0, 0, 0, 0))

    # 1100 us is 7 % throttle with RC3_MIN 1000 and RC3_DZ 30: too high to arm in STABILIZE
    m = _with_rc(c, _rc(ch3=1100), "STATUSTEXT", lambda m: "Throttle too high" in m.text,
                 send=send_arm)
    assert m is not None
    # calibrated: 1100 us is the bottom of the stick, so arming is accepted
    _set(c, "RC3_MIN", 1100, mav.MAV_PARAM_TYPE_INT16)
    ack = _with_rc(c, _rc(ch3=1100), "COMMAND_ACK",
                   lambda m: m.command == arm and m.result == mav.MAV_RESULT_ACCEPTED,
                   send=send_arm)
    assert ack is not None
    c.drain()
    c.send(mav.MAVLink_command_long_message(1, 1, arm, 0, 0, 0, 0, 0, 0, 0, 0))
    assert wait_for(c, "HEARTBEAT", lambda m: not m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED,
                    timeout_s=10) is not None
    _set(c, "RC3_MIN", 1000, mav.MAV_PARAM_TYPE_INT16)


def test_fltmode_channel_switches_modes(vehicle):
    v, c = vehicle
    _set(c, "FLTMODE_CH", 8, mav.MAV_PARAM_TYPE_INT8)
    _set(c, "FLTMODE3", 2, mav.MAV_PARAM_TYPE_INT8)            # position 2 (1361-1490 us)
    _set(c, "FLTMODE1", 0, mav.MAV_PARAM_TYPE_INT8)            # position 0 (up to 1230 us)
    hb = _with_rc(c, _rc(ch3=1000, ch8=1425), "HEARTBEAT", lambda m: m.custom_mode == 2)
    assert hb is not None, "the mode switch did not select ALT_HOLD"
    hb = _with_rc(c, _rc(ch3=1000, ch8=1100), "HEARTBEAT", lambda m: m.custom_mode == 0)
    assert hb is not None, "the mode switch did not select STABILIZE"
    # an unknown mode on a switch position: refused with a STATUSTEXT, the mode stays
    _set(c, "FLTMODE6", 27, mav.MAV_PARAM_TYPE_INT8)
    m = _with_rc(c, _rc(ch3=1000, ch8=1900), "STATUSTEXT",
                 lambda m: "mode change failed" in m.text.lower())
    assert m is not None
    c.drain()
    assert wait_for(c, "HEARTBEAT", timeout_s=5).custom_mode == 0
