"""GUIDED/offboard inputs reach the vehicle decoded; MANUAL_CONTROL and RC overrides only from
SYSID_MYGCS; setpoints in frames we do not fly are counted and dropped."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

from mavtest_client import wait_until
from mavtest_vehicle import DeclaredParamStore, KinematicVehicle

from silbridge.mavlink.gcs.vehicle_api import ParamStore, VehicleCommands


def test_test_vehicle_implements_the_protocols():
    assert isinstance(KinematicVehicle(), VehicleCommands)
    assert isinstance(DeclaredParamStore(), ParamStore)


def test_position_and_attitude_targets(env):
    c = env.client
    c.send(mav.MAVLink_set_position_target_local_ned_message(
        1000, 1, 1, mav.MAV_FRAME_LOCAL_NED, 0b0000_1111_1111_1000, 1.0, 2.0, -3.0,
        0, 0, 0, 0, 0, 0, 0.5, 0))
    c.send(mav.MAVLink_set_position_target_global_int_message(
        1001, 1, 1, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 0b0000_1111_1111_1000,
        -353630000, 1491650000, 15.0, 0, 0, 0, 0, 0, 0, 0, 0))
    c.send(mav.MAVLink_set_attitude_target_message(
        1002, 1, 1, 0b0000_0111, [1.0, 0.0, 0.0, 0.0], 0, 0, 0, 0.6))
    c.send(mav.MAVLink_set_position_target_local_ned_message(        # frame we do not fly:
        1003, 1, 1, mav.MAV_FRAME_GLOBAL, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0))  # vehicle stops
    v = env.vehicle
    assert wait_until(lambda: v.calls_named("set_attitude_target"))
    assert wait_until(lambda: len(v.calls_named("set_position_target")) == 3)
    local, glob, bad = [a[0] for a in v.calls_named("set_position_target")]
    assert bad.frame == mav.MAV_FRAME_GLOBAL and not bad.is_global
    assert not local.is_global and (local.x, local.y, local.z) == (1.0, 2.0, -3.0)
    assert local.type_mask == 0b0000_1111_1111_1000 and math.isclose(local.yaw_rad, 0.5)
    assert local.source_system == 255
    assert glob.is_global and (glob.x, glob.y, glob.z) == (-353630000, 1491650000, 15.0)
    att = v.calls_named("set_attitude_target")[0][0]
    assert att.q_wxyz == (1.0, 0.0, 0.0, 0.0) and math.isclose(att.thrust, 0.6, rel_tol=1e-6)


def test_manual_control_and_rc_override_only_from_my_gcs(env):
    env.client.send(mav.MAVLink_manual_control_message(1, 100, -200, 500, 0, 1))
    env.client.send(mav.MAVLink_rc_channels_override_message(1, 1, 1500, 1600, 1000, 1500,
                                                              0, 0, 0, 0))
    other = env.new_client(sysid=77)
    other.send(mav.MAVLink_manual_control_message(1, 1, 1, 1, 1, 0))
    other.close()
    v = env.vehicle
    assert wait_until(lambda: v.calls_named("rc_override"))
    assert wait_until(lambda: env.server.counters().get("setpoints_rejected", 0) == 1)
    assert v.calls_named("manual_control") == [(100, -200, 500, 0, 1)]
    assert v.calls_named("rc_override")[0][0][:4] == (1500, 1600, 1000, 1500)
