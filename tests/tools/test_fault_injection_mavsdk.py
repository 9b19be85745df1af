"""MAVSDK's Failure plugin (the C++ core through its 4.x Python binding) injects into our FC as
PX4 users do: `silbridge fly --speed 8` with JSBSim physics, MAVLink on a private port.

SYS_FAILURE_EN 0 -> DENIED; a unit we cannot map -> UNSUPPORTED; GPS OFF -> the bridge's
receiver goes silent, the FC's GPS_RAW_INT (MAVSDK's gps_info) loses its fix and its health
says no global position; GPS OK brings both back.
"""

from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from waits import until  # noqa: E402

from sitl_helpers import SitlVehicle, free_udp_port  # noqa: E402

mavsdk = pytest.importorskip("mavsdk")
if not hasattr(mavsdk, "Mavsdk"):
    pytest.skip("these tests use the MAVSDK 4.x Python binding (pip install 'mavsdk>=4')",
                allow_module_level=True)

from mavsdk import ComponentType, Configuration, Mavsdk  # noqa: E402
from mavsdk.plugins.failure import (Failure, FailureError, FailureResult, FailureType,  # noqa: E402
                                    FailureUnit)
from mavsdk.plugins.param import Param  # noqa: E402
from mavsdk.plugins.telemetry import FixType, Telemetry  # noqa: E402

mavsdk.log_subscribe(lambda level, msg, file, line: True)    # keep MAVSDK's log quiet


def _result(call) -> FailureResult:
    try:
        return call()
    except FailureError as e:
        return e.result


def test_mavsdk_failure_plugin_gps_off_and_back():
    port = free_udp_port()
    v = SitlVehicle([f"udpout:127.0.0.1:{port}"], speed=8.0, processes=2)
    m = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    try:
        m.add_any_connection(f"udpin://127.0.0.1:{port}")
        system = m.first_autopilot(30.0)
        assert system is not None, "MAVSDK found no autopilot"
        tel, failure, param = Telemetry(system), Failure(system), Param(system)
        tel.set_rate_gps_info(10.0)
        fixed = (FixType.FIX_3D, FixType.FIX_DGPS, FixType.RTK_FLOAT, FixType.RTK_FIXED)
        assert until(lambda: tel.gps_info().fix_type in fixed, 60.0), tel.gps_info()
        assert until(lambda: tel.health().is_global_position_ok, 60.0), tel.health()

        gps_off = lambda: failure.inject(FailureUnit.SENSOR_GPS, FailureType.OFF, 0)  # noqa: E731
        assert _result(gps_off) == FailureResult.DENIED          # SYS_FAILURE_EN 0, as PX4
        param.set_param_int("SYS_FAILURE_EN", 1)
        assert _result(lambda: failure.inject(FailureUnit.SENSOR_OPTICAL_FLOW, FailureType.OFF,
                                              0)) == FailureResult.UNSUPPORTED
        assert _result(gps_off) == FailureResult.SUCCESS
        assert until(lambda: tel.gps_info().fix_type not in fixed, 30.0), tel.gps_info()
        assert until(lambda: not tel.health().is_global_position_ok, 30.0), tel.health()

        assert _result(lambda: failure.inject(FailureUnit.SENSOR_GPS, FailureType.OK, 0)) \
            == FailureResult.SUCCESS
        assert until(lambda: tel.gps_info().fix_type in fixed, 30.0), tel.gps_info()
        assert until(lambda: tel.health().is_global_position_ok, 30.0), tel.health()
        assert v.alive()
    finally:
        m.destroy()
        v.stop()
