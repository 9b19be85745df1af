"""MAVProxy's `param set SIM_GPS_DISABLE 1` on our FC, as on ArduCopter SITL: the bridge's GNSS
receiver goes silent and GPS_RAW_INT loses its fix; `param set SIM_GPS_DISABLE 0` brings it back.
"""

from __future__ import annotations

import os
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_port  # noqa: E402
from test_mavlink_mavproxy import MAVPROXY, MavProxy  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402

pytestmark = pytest.mark.skipif(not os.path.exists(MAVPROXY), reason="MAVProxy not installed")


def _fix_type(mp: MavProxy) -> int | None:
    """GPS_RAW_INT.fix_type as MAVProxy's `status` shows it (None: not shown in time)."""
    mp.send("status GPS_RAW_INT")
    try:
        return int(mp.expect(r"GPS_RAW_INT \{.*fix_type : (\d+)", 3.0).group(1))
    except AssertionError:
        return None


def _until_fix(mp: MavProxy, ok, timeout_s: float = 30.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        f = _fix_type(mp)
        if f is not None and ok(f):
            return True
        time.sleep(0.3)
    return False


def test_mavproxy_sim_gps_disable_switches_the_gnss_off_and_on(tmp_path):
    port = free_udp_port()
    v = SitlVehicle([f"udpout:127.0.0.1:{port}"], speed=8.0, processes=2)
    mp = MavProxy(port, str(tmp_path))
    try:
        mp.expect(rf"Received {len(P.PARAMS)} parameters", 60.0)
        mp.send("set streamrate 5")
        mp.expect(r"GPS lock at", 30.0)     # MAVProxy saw a 3D fix in GPS_RAW_INT
        assert _until_fix(mp, lambda f: f >= 3), "no 3D fix to start from"
        mp.send("param set SIM_GPS_DISABLE 1")
        assert _until_fix(mp, lambda f: f < 3), "SIM_GPS_DISABLE 1 did not silence the GNSS"
        mp.send("param set SIM_GPS_DISABLE 0")
        assert _until_fix(mp, lambda f: f >= 3), "the fix did not come back"
    except AssertionError as exc:
        raise AssertionError(f"{exc}\nthe vehicle said:\n{v.stop()[-3000:]}") from None
    finally:
        mp.close()
        err = v.stop()
    assert "Traceback" not in err, err[-3000:]
