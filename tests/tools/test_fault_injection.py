"""The ways in on our FC: MAV_CMD_INJECT_FAILURE as PX4 1.15 accepts it and ArduPilot's SIM_*
parameters, each reaching the bridge's fault engine and showing in what the FC reads.

Real processes: `silbridge fly --speed 8` (bridge + our FC with its MAVLink vehicle), a
pymavlink GCS on a private loopback port. A GNSS fault is applied by the bridge's GNSS model,
so the FC's GPS_RAW_INT changing is the proof that the FC's FAULT record reached the bridge.
"""

from __future__ import annotations

import os
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port, gcs_for, wait_for  # noqa: E402

INJECT = mav.MAV_CMD_INJECT_FAILURE
GPS, OPTICAL_FLOW = mav.FAILURE_UNIT_SENSOR_GPS, mav.FAILURE_UNIT_SENSOR_OPTICAL_FLOW
OK, OFF, SLOW = mav.FAILURE_TYPE_OK, mav.FAILURE_TYPE_OFF, mav.FAILURE_TYPE_SLOW


def _vehicle(processes: int, extra=()):
    port = free_udp_port()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=8.0, processes=processes,
                    extra=list(extra))
    c = gcs_for(port)
    # GPS_RAW_INT at 10 Hz (sim time)
    c.command_long(mav.MAV_CMD_SET_MESSAGE_INTERVAL, mav.MAVLINK_MSG_ID_GPS_RAW_INT, 100_000)
    return v, c


def _param_set(c, name: str, value: float, ptype=mav.MAV_PARAM_TYPE_INT32):
    c.send(mav.MAVLink_param_set_message(1, 1, name.encode(), value, ptype))
    m = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == name, 10.0)
    assert m is not None and m.param_value == pytest.approx(value), (name, m)


def _inject(c, unit: int, ftype: int, instance: int = 0):
    for _ in range(3):      # UDP: a lost command or ACK is sent again, as MAVSDK does
        ack = c.command_long(INJECT, unit, ftype, instance, timeout_s=3.0)
        if ack is not None:
            return ack.result
    raise AssertionError("no COMMAND_ACK for MAV_CMD_INJECT_FAILURE")


def _fix(c, cond, timeout_s: float = 30.0):
    return wait_for(c, "GPS_RAW_INT", lambda m: cond(m.fix_type), timeout_s)


@pytest.fixture
def shm_vehicle():
    v, c = _vehicle(processes=2)
    yield v, c
    c.close()
    v.stop()


def test_inject_failure_denied_unsupported_accepted_and_reaches_the_bridge(shm_vehicle):
    v, c = shm_vehicle
    assert _fix(c, lambda f: f >= 3) is not None, "no 3D fix to start from"
    # SYS_FAILURE_EN 0 (the default, as PX4): refused, nothing switched
    assert _inject(c, GPS, OFF) == mav.MAV_RESULT_DENIED
    assert wait_for(c, "STATUSTEXT", lambda m: "SYS_FAILURE_EN" in m.text, 5.0) is not None
    assert _fix(c, lambda f: f < 3, 3.0) is None
    _param_set(c, "SYS_FAILURE_EN", 1)
    # a unit and a type we cannot map
    assert _inject(c, OPTICAL_FLOW, OFF) == mav.MAV_RESULT_UNSUPPORTED
    assert _inject(c, GPS, SLOW) == mav.MAV_RESULT_UNSUPPORTED
    assert _inject(c, mav.FAILURE_UNIT_SYSTEM_MOTOR, OFF, instance=7) == \
        mav.MAV_RESULT_UNSUPPORTED      # a quad X has motors 1..4
    # GPS off: the bridge's receiver goes silent, the FC's GPS_RAW_INT loses its fix
    assert _inject(c, GPS, OFF) == mav.MAV_RESULT_ACCEPTED
    assert _fix(c, lambda f: f < 3) is not None, "GPS OFF did not reach the GNSS the FC reads"
    # FAILURE_TYPE_OK clears it
    assert _inject(c, GPS, OK) == mav.MAV_RESULT_ACCEPTED
    assert _fix(c, lambda f: f >= 3) is not None, "the fix did not come back after GPS OK"
    assert v.alive()


def _lat_median(c, n: int = 15) -> float:
    lats = []
    while len(lats) < n:
        m = wait_for(c, "GPS_RAW_INT", lambda m: m.fix_type >= 3, 10.0)
        assert m is not None, "no 3D fix"
        lats.append(m.lat)
    return sorted(lats)[n // 2]


def test_sim_gps_glitch_shifts_the_gnss_and_clearing_restores_it(shm_vehicle):
    v, c = shm_vehicle
    base = _lat_median(c)
    # ArduPilot's SIM_GPS_GLITCH_X is a latitude offset in degrees: 1e-4 deg = 1000 degE7
    _param_set(c, "SIM_GPS_GLITCH_X", 1e-4, mav.MAV_PARAM_TYPE_REAL32)
    assert wait_for(c, "GPS_RAW_INT", lambda m: m.lat - base > 700, 20.0) is not None, \
        "the glitch did not reach the GNSS the FC reads"
    shifted = _lat_median(c)
    assert abs(shifted - base - 1000) < 150, (base, shifted)    # ~11 m north, GNSS noise aside
    _param_set(c, "SIM_GPS_GLITCH_X", 0.0, mav.MAV_PARAM_TYPE_REAL32)
    assert wait_for(c, "GPS_RAW_INT", lambda m: abs(m.lat - base) < 300, 20.0) is not None
    assert abs(_lat_median(c) - base) < 150
    assert v.alive()


def test_inject_failure_over_the_udp_hil_link_reaches_the_bridge():
    v, c = _vehicle(processes=2, extra=["--transport", "udp"])
    try:
        assert _fix(c, lambda f: f >= 3) is not None, "no 3D fix to start from"
        _param_set(c, "SYS_FAILURE_EN", 1)
        assert _inject(c, GPS, OFF) == mav.MAV_RESULT_ACCEPTED
        assert _fix(c, lambda f: f < 3) is not None, "GPS OFF did not cross the HIL link"
        assert _inject(c, GPS, OK) == mav.MAV_RESULT_ACCEPTED
        assert _fix(c, lambda f: f >= 3) is not None
        assert v.alive()
    finally:
        c.close()
        v.stop()


GUIDED, ALT_HOLD, RTL = 4, 2, 6
ACCEPTED = mav.MAV_RESULT_ACCEPTED


def _cmd(c, command, *p):
    c.drain()
    ack = c.command_long(command, *p, timeout_s=3.0)
    assert ack is not None, f"no COMMAND_ACK for {command}"
    return ack.result


def _fly_guided(c, alt_m: float = 5.0) -> None:
    for mid, hz in ((mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 10),
                    (mav.MAVLINK_MSG_ID_SYS_STATUS, 5)):
        c.command_long(mav.MAV_CMD_SET_MESSAGE_INTERVAL, mid, 1e6 / hz)
    bit = mav.MAV_SYS_STATUS_PREARM_CHECK
    assert wait_for(c, "SYS_STATUS", lambda m: m.onboard_control_sensors_health & bit,
                    timeout_s=60.0) is not None, "pre-arm checks never passed"
    assert _cmd(c, mav.MAV_CMD_DO_SET_MODE, 1, GUIDED) == ACCEPTED
    assert _cmd(c, mav.MAV_CMD_COMPONENT_ARM_DISARM, 1) == ACCEPTED
    assert _cmd(c, mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, alt_m) == ACCEPTED
    assert wait_for(c, "GLOBAL_POSITION_INT", lambda m: m.relative_alt > (alt_m - 0.5) * 1000,
                    timeout_s=60.0) is not None, "take-off did not reach its altitude"


def test_injected_gcs_loss_is_silence_both_ways_fs_gcs_fires_and_it_ends(shm_vehicle):
    v, c = shm_vehicle
    _param_set(c, "SYS_FAILURE_EN", 1)
    _param_set(c, "FS_GCS_ENABLE", 1, mav.MAV_PARAM_TYPE_INT8)
    # both sim time: at --speed 8 our heartbeats (every 0.5 s of wall time while waiting)
    # are 4 s of sim time apart, well inside 20 s; the injected loss lasts 40 s
    _param_set(c, "FS_GCS_TIMEOUT", 20.0, mav.MAV_PARAM_TYPE_REAL32)
    _param_set(c, "SB_FI_GCS_S", 40.0, mav.MAV_PARAM_TYPE_REAL32)
    _fly_guided(c)
    # the command's ACK and the STATUSTEXT saying so still go out, then nothing
    assert _inject(c, mav.FAILURE_UNIT_SYSTEM_MAVLINK_SIGNAL, OFF) == ACCEPTED
    assert wait_for(c, "STATUSTEXT", lambda m: "injected: gcs lost" in m.text, 3.0) is not None
    c.collect(0.2)              # what was already on its way
    c.drain()
    # we keep sending heartbeats (wait_for does): the FC does not hear them
    assert wait_for(c, "HEARTBEAT", timeout_s=0.5) is None, "the FC was still heard"
    # 40 s of sim time later the loss ends by itself (the GCS could not clear it)
    assert wait_for(c, "STATUSTEXT", lambda m: "cleared: gcs lost" in m.text, 60.0) is not None
    # FS_GCS fired while it was lost, although our heartbeats never stopped: RTL
    assert wait_for(c, "HEARTBEAT", lambda m: m.custom_mode == RTL, 5.0) is not None
    assert v.alive()


def test_injected_rc_loss_triggers_the_radio_failsafe(shm_vehicle):
    v, c = shm_vehicle
    _param_set(c, "SYS_FAILURE_EN", 1)
    _fly_guided(c)
    sticks = mav.MAVLink_rc_channels_override_message(1, 1, 1500, 1500, 1500, 1500,
                                                      *([0] * 14))
    c.send(sticks)
    assert _cmd(c, mav.MAV_CMD_DO_SET_MODE, 1, ALT_HOLD) == ACCEPTED
    assert _inject(c, mav.FAILURE_UNIT_SYSTEM_RC_SIGNAL, OFF) == ACCEPTED
    # the pilot's radio keeps sending; the FC's receiver hears none of it
    fs = None
    for _ in range(40):
        c.send(sticks)
        fs = wait_for(c, "STATUSTEXT", lambda m: m.text == "Radio Failsafe", 0.1)
        if fs is not None:
            break
    assert fs is not None, "no radio failsafe while RC was lost"
    assert wait_for(c, "HEARTBEAT", lambda m: m.custom_mode == RTL, 5.0) is not None
    assert _inject(c, mav.FAILURE_UNIT_SYSTEM_RC_SIGNAL, OK) == ACCEPTED
    assert wait_for(c, "STATUSTEXT", lambda m: "cleared: rc lost" in m.text, 3.0) is not None
    assert v.alive()


def test_scenario_failure_of_an_fc_side_unit_reaches_our_fc(tmp_path):
    """[[failure]] unit rc: the bridge only reports it; the glue (fc_param_events.py) hands
    it to the FC, over the `silbridge fc --param-at` arguments of `fly --processes 2`."""
    path = tmp_path / "rc_lost.toml"
    path.write_text('name = "rc lost"\nseed = 3\nduration_s = 600.0\n'
                    '[[failure]]\nunit = "rc"\ntype = "lost"\nat_s = 12.0\nduration_s = 8.0\n')
    v, c = _vehicle(processes=2, extra=["--scenario", str(path)])
    try:
        on = wait_for(c, "STATUSTEXT", lambda m: "injected: rc lost" in m.text, 30.0)
        assert on is not None, "the scenario's rc loss never reached the FC"
        off = wait_for(c, "STATUSTEXT", lambda m: "cleared: rc lost" in m.text, 30.0)
        assert off is not None, "the scenario's rc loss did not end at its duration"
        # sim time between the two (SYSTEM_TIME is not streamed: the PARAM tells the state)
        c.send(mav.MAVLink_param_request_read_message(1, 1, b"SIM_RC_FAIL", -1))
        m = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == "SIM_RC_FAIL", 10.0)
        assert m is not None and m.param_value == 0.0
    finally:
        c.close()
        v.stop()
