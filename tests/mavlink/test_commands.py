"""COMMAND_LONG / COMMAND_INT -> COMMAND_ACK through the real server and the test vehicle."""

from __future__ import annotations

import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import CopterMode


def test_ack_echoes_sender_and_unknown_is_unsupported(env):
    ack = env.client.command_long(31999)   # no such command
    assert ack is not None
    assert ack.result == mav.MAV_RESULT_UNSUPPORTED
    assert (ack.target_system, ack.target_component) == (255, 190)
    other = env.new_client(sysid=245, compid=190)     # MAVSDK's default ids
    ack = other.command_long(mav.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, p1=1)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert (ack.target_system, ack.target_component) == (245, 190)
    other.close()


def test_command_for_another_system_is_ignored(env):
    assert env.client.command_long(mav.MAV_CMD_NAV_LAND, target=(7, 1), timeout_s=0.3) is None
    # Not only no ACK: the vehicle never ran it, and the same command for us still runs, once.
    assert env.vehicle.calls_named("land") == []
    ack = env.client.command_long(mav.MAV_CMD_NAV_LAND)
    assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED
    assert len(env.vehicle.calls_named("land")) == 1


def test_arm_refused_by_prearm_with_statustext_then_forced(env):
    env.vehicle.prearm_ok = False
    ack = env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1)
    assert ack.result == mav.MAV_RESULT_FAILED
    texts = [m.text for m in env.client.history if m.get_type() == "STATUSTEXT"]
    assert any("PreArm: Gyros not calibrated" in t for t in texts)
    ack = env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1, p2=2989)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.calls_named("arm") == [(False,), (True,)]
    hb = env.client.wait("HEARTBEAT", lambda m: m.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED,
                         timeout_s=2.5)
    assert hb is not None


def test_disarm_force_code(env):
    env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1)
    env.client.command_long(mav.MAV_CMD_DO_SET_MODE, p1=1, p2=CopterMode.GUIDED)
    assert env.client.command_long(mav.MAV_CMD_NAV_TAKEOFF, p7=10).result == 0
    ack = env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=0)
    assert ack.result == mav.MAV_RESULT_DENIED
    ack = env.client.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=0, p2=21196)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.calls_named("disarm") == [(False,), (True,)]


def test_set_mode_128_bit_is_not_an_arm_request(env):
    ack = env.client.command_long(mav.MAV_CMD_DO_SET_MODE, p1=1 | 128, p2=CopterMode.LOITER)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.calls_named("set_mode") == [(CopterMode.LOITER,)]
    assert env.vehicle.calls_named("arm") == []
    ack = env.client.command_long(mav.MAV_CMD_DO_SET_MODE, p1=0, p2=CopterMode.LOITER)
    assert ack.result == mav.MAV_RESULT_DENIED
    hb = env.client.wait("HEARTBEAT", lambda m: m.custom_mode == CopterMode.LOITER, 2.5)
    assert hb is not None and hb.autopilot == mav.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert hb.type == mav.MAV_TYPE_QUADROTOR


def test_set_mode_message(env):
    env.client.send(mav.MAVLink_set_mode_message(1, 1, CopterMode.ALT_HOLD))
    ack = env.client.wait("COMMAND_ACK", lambda m: m.command == mav.MAVLINK_MSG_ID_SET_MODE)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.mode == CopterMode.ALT_HOLD


def test_takeoff_land_rtl_mission_start(env):
    c = env.client
    assert c.command_long(mav.MAV_CMD_NAV_TAKEOFF, p7=10).result == mav.MAV_RESULT_FAILED
    assert c.command_long(mav.MAV_CMD_NAV_TAKEOFF, p7=float("nan")).result == \
        mav.MAV_RESULT_DENIED
    c.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1)
    c.command_long(mav.MAV_CMD_DO_SET_MODE, p1=1, p2=CopterMode.GUIDED)
    assert c.command_long(mav.MAV_CMD_NAV_TAKEOFF, p7=10).result == mav.MAV_RESULT_ACCEPTED
    ess = c.wait("EXTENDED_SYS_STATE", lambda m: m.landed_state == mav.MAV_LANDED_STATE_IN_AIR,
                 timeout_s=3.0)
    assert ess is not None
    assert c.command_long(mav.MAV_CMD_NAV_LAND).result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.mode == CopterMode.LAND
    assert c.command_long(mav.MAV_CMD_NAV_RETURN_TO_LAUNCH).result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.mode == CopterMode.RTL
    # no mission yet: the vehicle refuses and says why
    assert c.command_long(mav.MAV_CMD_MISSION_START).result == mav.MAV_RESULT_FAILED


def test_reposition_int_and_change_speed(env):
    c = env.client
    c.command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, p1=1)
    c.command_long(mav.MAV_CMD_DO_SET_MODE, p1=1, p2=CopterMode.GUIDED)
    c.command_long(mav.MAV_CMD_NAV_TAKEOFF, p7=5)
    ack = c.command_int(mav.MAV_CMD_DO_REPOSITION, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                        p1=-1, p4=float("nan"), x=-353630000, y=1491650000, z=20.0)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    args = env.vehicle.calls_named("reposition")[-1]
    assert args[:4] == (-353630000, 1491650000, 20.0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
    ack = c.command_int(mav.MAV_CMD_DO_REPOSITION, mav.MAV_FRAME_LOCAL_NED, x=1, y=2, z=3)
    assert ack.result == mav.MAV_RESULT_DENIED
    ack = c.command_long(mav.MAV_CMD_DO_CHANGE_SPEED, p1=1, p2=7.5, p3=-1)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    assert env.vehicle.calls_named("change_speed")[-1] == (7.5, 1)


def test_request_message_and_home(env):
    c = env.client
    ack = c.command_long(mav.MAV_CMD_REQUEST_MESSAGE, p1=mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    av = c.wait("AUTOPILOT_VERSION")
    assert av.flight_sw_version >> 24 == 4 and av.flight_sw_version & 0xFF == 255
    for bit in (mav.MAV_PROTOCOL_CAPABILITY_MISSION_INT, mav.MAV_PROTOCOL_CAPABILITY_COMMAND_INT,
                mav.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT, mav.MAV_PROTOCOL_CAPABILITY_MAVLINK2,
                mav.MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET):
        assert av.capabilities & bit
    assert not av.capabilities & mav.MAV_PROTOCOL_CAPABILITY_FTP
    assert av.capabilities & mav.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
    assert av.capabilities & mav.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
    assert bytes(av.flight_custom_version) == b"deadbeef"
    ack = c.command_long(mav.MAV_CMD_GET_HOME_POSITION)
    assert ack.result == mav.MAV_RESULT_ACCEPTED
    home = c.wait("HOME_POSITION")
    assert (home.latitude, home.longitude) == (-353632621, 1491652374)
    ack = c.command_long(mav.MAV_CMD_REQUEST_MESSAGE, p1=60000)
    assert ack.result == mav.MAV_RESULT_FAILED          # ArduCopter 4.6 for an unknown id


def test_a_stalled_vehicle_still_gets_an_ack_temporarily_rejected(env):
    env.vehicle.service_enabled = False          # the vehicle loop stops draining its queue
    # An answer, not silence: the server withdraws the call (at 0.4 s) and says so, within
    # command_long's wait (no timing is asserted beyond that).
    ack = env.client.command_long(mav.MAV_CMD_NAV_LAND)
    assert ack is not None and ack.result == mav.MAV_RESULT_TEMPORARILY_REJECTED
    env.vehicle.service_enabled = True
    time.sleep(0.05)
    assert env.vehicle.calls_named("land") == []   # the withdrawn call never ran
    assert env.client.command_long(mav.MAV_CMD_NAV_LAND).result == mav.MAV_RESULT_ACCEPTED


def test_retransmitted_command_gets_one_ack(env):
    env.vehicle.service_enabled = False
    msg = mav.MAVLink_command_long_message(1, 1, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH, 0,
                                           0, 0, 0, 0, 0, 0, 0)
    env.client.send(msg)
    env.client.send(msg)
    time.sleep(0.1)
    env.vehicle.service_enabled = True
    msgs = env.client.collect(0.6)
    acks = [m for m in msgs if m.get_type() == "COMMAND_ACK"]
    assert len(acks) == 1 and acks[0].result == mav.MAV_RESULT_ACCEPTED
    assert len(env.vehicle.calls_named("rtl")) == 1
