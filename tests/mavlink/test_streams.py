"""Telemetry: defaults without asking, SET_MESSAGE_INTERVAL and REQUEST_DATA_STREAM rates
(measured loosely: counts within wide bounds, never tight timing), health bits, PID_TUNING."""

from __future__ import annotations

import collections

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.vehicle_api import SensorBit

from mavtest_client import GcsClient

M = mav


def counts(msgs):
    return collections.Counter(m.get_type() for m in msgs)


def test_defaults_unprompted_1hz(env):
    c = counts(env.client.collect(2.2))
    for t in ("HEARTBEAT", "SYS_STATUS", "EXTENDED_SYS_STATE", "MISSION_CURRENT", "SYSTEM_TIME"):
        assert 1 <= c[t] <= 4, (t, c[t])
    assert c["ATTITUDE"] == 0 and c["GLOBAL_POSITION_INT"] == 0


def test_set_message_interval_rates(env):
    cl = env.client
    assert cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_ATTITUDE,
                           p2=20_000).result == M.MAV_RESULT_ACCEPTED           # 50 Hz
    assert cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL,
                           p1=M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
                           p2=100_000).result == M.MAV_RESULT_ACCEPTED          # 10 Hz
    assert cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_SYS_STATUS,
                           p2=-1).result == M.MAV_RESULT_ACCEPTED               # off
    assert cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=60000,
                           p2=1000).result == M.MAV_RESULT_DENIED          # as ArduCopter 4.6
    cl.drain()
    c = counts(cl.collect(1.0))
    assert 25 <= c["ATTITUDE"] <= 60, c["ATTITUDE"]
    assert 5 <= c["GLOBAL_POSITION_INT"] <= 13, c["GLOBAL_POSITION_INT"]
    assert c["SYS_STATUS"] == 0
    cl.send(M.MAVLink_command_long_message(1, 1, M.MAV_CMD_GET_MESSAGE_INTERVAL, 0,
                                           M.MAVLINK_MSG_ID_ATTITUDE, 0, 0, 0, 0, 0, 0))
    mi = cl.wait("MESSAGE_INTERVAL")
    assert mi.message_id == M.MAVLINK_MSG_ID_ATTITUDE and mi.interval_us == 20_000
    # 0 = back to the default (off for ATTITUDE)
    cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_ATTITUDE, p2=0)
    cl.collect(0.1)
    cl.drain()
    assert counts(cl.collect(0.5))["ATTITUDE"] == 0


def test_request_data_stream_groups(env):
    cl = env.client
    cl.send(M.MAVLink_request_data_stream_message(1, 1, M.MAV_DATA_STREAM_ALL, 4, 1))
    cl.send(M.MAVLink_request_data_stream_message(1, 1, M.MAV_DATA_STREAM_EXTRA1, 10, 1))
    cl.collect(0.3)
    cl.drain()
    c = counts(cl.collect(1.5))
    for t in ("RAW_IMU", "SCALED_PRESSURE", "GPS_RAW_INT", "NAV_CONTROLLER_OUTPUT",
              "GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "SERVO_OUTPUT_RAW", "RC_CHANNELS",
              "VFR_HUD", "BATTERY_STATUS", "VIBRATION"):
        assert 3 <= c[t] <= 9, (t, c[t])               # 4 Hz for 1.5 s
    assert 10 <= c["ATTITUDE"] <= 20, c["ATTITUDE"]     # 10 Hz
    cl.send(M.MAVLink_request_data_stream_message(1, 1, M.MAV_DATA_STREAM_POSITION, 0, 0))
    cl.collect(0.3)
    cl.drain()
    c = counts(cl.collect(0.6))
    assert c["GLOBAL_POSITION_INT"] == 0 and c["VFR_HUD"] >= 1


def test_streams_are_per_link(make_env):
    # Two endpoints, one ground station on each: a rate one of them asks for is that link's
    # alone. (Two clients of one udpin endpoint would be one link: it answers the last sender.)
    env = make_env(endpoints=["udpin:127.0.0.1:0", "udpin:127.0.0.2:0"])
    first = env.client                                    # on 127.0.0.1
    other = GcsClient(env.server.local_addresses()["udpin:127.0.0.2:0"], sysid=245)
    try:
        other.send(other.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))
        assert other.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_VFR_HUD,
                                  p2=50_000).result == M.MAV_RESULT_ACCEPTED     # 20 Hz
        assert first.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_ATTITUDE,
                                  p2=50_000).result == M.MAV_RESULT_ACCEPTED     # 20 Hz
        first.drain()
        other.drain()
        got_other = counts(other.collect(0.5))
        got_first = counts(first.collect(0.2))      # includes what arrived meanwhile
        assert got_other["VFR_HUD"] >= 5 and got_first["ATTITUDE"] >= 5
        # Neither link received the other's rate (both messages are off by default).
        assert got_first["VFR_HUD"] == 0, got_first
        assert got_other["ATTITUDE"] == 0, got_other
    finally:
        other.close()


def test_contents_health_home_and_pid_tuning(env):
    cl = env.client
    st = cl.wait("SYS_STATUS", timeout_s=2.5)
    assert st.onboard_control_sensors_health & SensorBit.PREARM_CHECK
    assert st.voltage_battery == 16200 and st.current_battery == 1250
    assert st.battery_remaining == 87
    env.vehicle.prearm_ok = False
    st = cl.wait("SYS_STATUS", lambda m: not m.onboard_control_sensors_health
                 & SensorBit.PREARM_CHECK, timeout_s=2.5)
    assert st is not None
    hp = [m for m in cl.history if m.get_type() == "HOME_POSITION"]
    assert hp and hp[0].latitude == -353632621          # announced unasked once home is set
    cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_PID_TUNING, p2=50_000)
    cl.collect(0.2)
    cl.drain()
    assert counts(cl.collect(0.3))["PID_TUNING"] == 0      # GCS_PID_MASK = 0
    env.params.set("GCS_PID_MASK", 0b0101)                  # roll and yaw
    cl.drain()
    axes = {m.axis for m in cl.collect(0.4) if m.get_type() == "PID_TUNING"}
    assert axes == {1, 3}
    cl.command_long(M.MAV_CMD_SET_MESSAGE_INTERVAL, p1=M.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
                    p2=100_000)
    gp = cl.wait("GLOBAL_POSITION_INT")
    assert gp.hdg == 9000 and gp.lat == -353632621


def test_statustext_from_vehicle_and_chunking(env):
    env.server.send_statustext(M.MAV_SEVERITY_INFO, "EKF3 IMU0 is using GPS")
    m = env.client.wait("STATUSTEXT", lambda m: "EKF3" in m.text)
    assert m.severity == M.MAV_SEVERITY_INFO and m.id == 0
    long = "x" * 60 + "END"
    env.server.send_statustext(M.MAV_SEVERITY_WARNING, long)
    a = env.client.wait("STATUSTEXT", lambda m: m.id != 0 and m.chunk_seq == 0)
    b = env.client.wait("STATUSTEXT", lambda m: m.id == a.id and m.chunk_seq == 1)
    assert a.text + b.text == long


def test_timesync_and_gcs_heartbeat_tracking(env):
    cl = env.client
    cl.send(M.MAVLink_timesync_message(0, 123456789))
    ts = cl.wait("TIMESYNC")
    assert ts.ts1 == 123456789 and ts.tc1 > 0
    assert env.server.seconds_since_gcs_heartbeat() < 1.0     # fixture sent one as sysid 255
    other = env.new_client(sysid=200)
    other.send(other.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))  # not SYSID_MYGCS: not counted
    other.close()
    import time
    time.sleep(0.3)
    assert env.server.seconds_since_gcs_heartbeat() >= 0.25
