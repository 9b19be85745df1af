"""MAVSDK 4.x (the C++ core through its Python binding) flies the real vehicle: `silbridge fly
--speed 8` with JSBSim physics and the SIL FC, MAVLink on a private loopback port.

MAVSDK listens (udpin) and the vehicle sends to it (udpout), as with ArduPilot SITL on 14540.
"""

from __future__ import annotations

import math
import os
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from waits import until  # noqa: E402

from sitl_helpers import SitlVehicle, free_udp_port  # noqa: E402

mavsdk = pytest.importorskip("mavsdk")
if not hasattr(mavsdk, "Mavsdk"):
    pytest.skip("these tests use the MAVSDK 4.x Python binding (pip install 'mavsdk>=4')",
                allow_module_level=True)

from mavsdk import ComponentType, Configuration, Mavsdk  # noqa: E402
from mavsdk.plugins.action import Action  # noqa: E402
from mavsdk.plugins.mission_raw import MissionItem, MissionRaw  # noqa: E402
from mavsdk.plugins.param import Param  # noqa: E402
from mavsdk.plugins.telemetry import Telemetry  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402

mavsdk.log_subscribe(lambda level, msg, file, line: True)    # keep MAVSDK's log quiet


@pytest.fixture
def drone():
    port = free_udp_port()
    # One process: the bridge's 1 s start-up rate check is then exact at --speed 8 (with the
    # FC in its own process that window is 125 ms of wall clock and scheduling noise decides).
    v = SitlVehicle([f"udpout:127.0.0.1:{port}"], speed=8.0, processes=1)
    m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    m.add_any_connection(f"udpin://127.0.0.1:{port}")
    system = m.first_autopilot(30.0)
    if system is None:
        m.destroy()
        raise AssertionError("MAVSDK found no autopilot; vehicle said:\n" + v.stop()[-3000:])
    tel = Telemetry(system)
    tel.set_rate_position(10.0)
    assert until(tel.health_all_ok, 60.0), f"health never all ok: {tel.health()}"
    yield dict(v=v, m=m, system=system, tel=tel, action=Action(system))
    m.destroy()
    v.stop()


def test_mavsdk_arm_takeoff_hold_land_disarm(drone):
    tel, action = drone["tel"], drone["action"]
    action.set_takeoff_altitude(10.0)
    action.arm()
    action.takeoff()
    assert until(lambda: tel.position().relative_altitude_m > 9.5, 60.0), "no take-off"
    assert until(tel.in_air, 5.0)
    alts = []
    end = time.monotonic() + 2.0                      # 16 s of hover at --speed 8
    while time.monotonic() < end:
        alts.append(tel.position().relative_altitude_m)
        time.sleep(0.1)
    assert 9.0 < min(alts) and max(alts) < 11.0, (min(alts), max(alts))
    action.land()
    assert until(lambda: not tel.armed(), 90.0), "did not land and disarm"
    assert until(lambda: not tel.in_air(), 5.0)
    assert drone["v"].alive()


def test_mavsdk_mission_raw_upload_and_fly_to_finished(drone):
    tel, action = drone["tel"], drone["action"]
    mission = MissionRaw(drone["system"])
    home = tel.position()
    lat0, lon0 = home.latitude_deg, home.longitude_deg
    m_per_deg_lat = 111_320.0
    m_per_deg_lon = m_per_deg_lat * math.cos(math.radians(lat0))

    def wp(seq, n, e, cmd=16, frame=3, z=10.0, current=0):
        return MissionItem(seq, frame, cmd, current, 1, 0.0, 0.0, 0.0, float("nan"),
                           int(round((lat0 + n / m_per_deg_lat) * 1e7)),
                           int(round((lon0 + e / m_per_deg_lon) * 1e7)), z, 0)

    items = [wp(0, 0, 0, frame=0, z=home.absolute_altitude_m),           # home
             wp(1, 0, 0, cmd=22, z=10.0, current=1),                      # take-off
             wp(2, 20, 0), wp(3, 20, 20), wp(4, 0, 20),
             MissionItem(5, 2, 20, 0, 1, 0, 0, 0, 0, 0, 0, 0.0, 0)]       # RTL
    mission.upload_mission(items)
    action.arm()
    mission.start_mission()
    assert until(lambda: tel.in_air(), 30.0)
    done = until(mission.is_mission_finished, 120.0, 0.5)
    assert done, f"mission not finished: {mission.mission_progress().current}"
    assert until(lambda: not tel.armed(), 60.0), "RTL did not land and disarm"
    p = tel.position()
    north = (p.latitude_deg - lat0) * m_per_deg_lat
    east = (p.longitude_deg - lon0) * m_per_deg_lon
    assert math.hypot(north, east) < 6.0


def test_mavsdk_params_all_and_set_get(drone):
    param = Param(drone["system"])
    allp = param.get_all_params()
    names = {p.name for p in allp.int_params} | {p.name for p in allp.float_params}
    assert len(names) == len(P.PARAMS)
    assert "DISARM_DELAY" in {p.name for p in allp.int_params}
    param.set_param_float("WPNAV_SPEED", 750.0)
    assert param.get_param_float("WPNAV_SPEED") == pytest.approx(750.0)
    param.set_param_int("DISARM_DELAY", 7)
    assert param.get_param_int("DISARM_DELAY") == 7
    param.set_param_int("GCS_PID_MASK", 3)
    assert param.get_param_int("GCS_PID_MASK") == 3
