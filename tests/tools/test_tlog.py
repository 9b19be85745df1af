"""`silbridge fly --tlog FILE`: the GCS link's MAVLink traffic in the standard tlog format.

The real vehicle (`fly --speed`, JSBSim + SIL FC + GCS server) talks to a pymavlink GCS;
the tlog it wrote is read back with pymavlink's mavutil.mavlink_connection (what
MAVExplorer uses) and with the mavlogdump.py script: both directions are in it, each
frame once, stamped with the wall clock in increasing order.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from sitl_helpers import SitlVehicle, free_udp_ports, gcs_for, wait_for  # noqa: E402


def _read_tlog(path) -> list:
    conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
    out = []
    while True:
        m = conn.recv_match()
        if m is None:
            return out
        out.append(m)


@pytest.mark.slow
def test_fly_tlog_holds_both_directions(tmp_path):
    tlog = tmp_path / "flight.tlog"
    port = free_udp_ports(1)[0]
    t_start = time.time()
    v = SitlVehicle([f"udpin:127.0.0.1:{port}"], speed=1.0,
                    extra=["--tlog", str(tlog)])
    try:
        c = gcs_for(port)
        assert wait_for(c, "HEARTBEAT", timeout_s=60) is not None, v.stop()[-3000:]
        c.send(c.mav.param_request_read_encode(1, 1, b"SYSID_THISMAV", -1))
        pv = wait_for(c, "PARAM_VALUE", lambda m: m.param_id == "SYSID_THISMAV", timeout_s=10)
        assert pv is not None
        ack = c.command_long(mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        assert ack is not None
        time.sleep(0.5)
        c.close()
    finally:
        err = v.stop()
    t_end = time.time()
    assert tlog.stat().st_size > 0, err[-3000:]

    msgs = _read_tlog(tlog)
    assert len(msgs) >= 10
    stamps = [m._timestamp for m in msgs]
    assert stamps == sorted(stamps), "tlog stamps go back in time"
    assert t_start - 1 <= stamps[0] and stamps[-1] <= t_end + 1, "not wall-clock stamps"
    vehicle = [m for m in msgs if m.get_srcSystem() == 1]
    gcs = [m for m in msgs if m.get_srcSystem() == 255]
    types_v = {m.get_type() for m in vehicle}
    types_g = {m.get_type() for m in gcs}
    assert {"HEARTBEAT", "PARAM_VALUE", "COMMAND_ACK"} <= types_v
    assert {"HEARTBEAT", "PARAM_REQUEST_READ", "COMMAND_LONG"} <= types_g
    assert not any(m.get_type() == "BAD_DATA" for m in msgs)
    # Each frame once: the vehicle's sequence numbers never repeat back to back.
    seqs = [m.get_seq() for m in vehicle]
    assert all(a != b for a, b in zip(seqs, seqs[1:]))

    # mavlogdump.py (pymavlink's script) reads it too.
    script = Path(sys.executable).with_name("mavlogdump.py")
    if not script.exists():
        pytest.skip("mavlogdump.py is not installed next to this Python")
    out = subprocess.run([sys.executable, str(script), "--types", "PARAM_VALUE", str(tlog)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "SYSID_THISMAV" in out.stdout
