"""MAV_CMD_DO_SET_HOME (QGroundControl's "Set Home Here", MAVProxy's `setHome`), on silbridge
and (SILBRIDGE_ARDUCOPTER set) the real ArduCopter 4.6, which must answer alike:

- a point (COMMAND_LONG: altitude above sea level) becomes home at once: ACCEPTED and a
  HOME_POSITION unasked; it stays while disarmed (home no longer follows the vehicle) and
  through arming; COMMAND_INT with a relative frame is above the current home; a latitude
  out of range is FAILED and leaves home where it was;
- altitudes a GCS gives afterwards are above the new home (the take-off, relative_alt), and
  RTL flies to it and lands there.
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, start  # noqa: E402
from gcs_session import Gcs, offset_e7  # noqa: E402


def _home(g: Gcs):
    since = time.monotonic()
    g.m.mav.command_long_send(1, 1, mav.MAV_CMD_GET_HOME_POSITION, 0, 0, 0, 0, 0, 0, 0, 0)
    assert g.wait_seen("HOME_POSITION", since, 5.0), "no HOME_POSITION on request"
    return g.last["HOME_POSITION"]


def _set_home(g: Gcs, *, lat_e7: int, lon_e7: int, alt_m: float, relative: bool = False):
    """The command and the HOME_POSITION sent with its ACK (None if none came)."""
    since = time.monotonic()
    if relative:
        g.m.mav.command_int_send(1, 1, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                                 mav.MAV_CMD_DO_SET_HOME, 0, 0, 0, 0, 0, 0, lat_e7, lon_e7,
                                 alt_m)
    else:
        g.m.mav.command_long_send(1, 1, mav.MAV_CMD_DO_SET_HOME, 0, 0, 0, 0, 0,
                                  lat_e7 * 1e-7, lon_e7 * 1e-7, alt_m)
    ack = g.wait("COMMAND_ACK", lambda a: a.command == mav.MAV_CMD_DO_SET_HOME, 5.0)
    unasked = g.wait_seen("HOME_POSITION", since, 2.0)
    return ack, (g.last["HOME_POSITION"] if unasked else None)



def _f32_e7(deg_e7: int) -> float:
    """COMMAND_LONG carries latitude and longitude as float32 degrees: they arrive within half
    a float32 step (at 149 deg, 76e-7 deg: 8 m); COMMAND_INT's integers arrive exactly."""
    return float(np.spacing(np.float32(abs(deg_e7) * 1e-7))) * 1e7 / 2 + 1


def _north_east_m(lat_e7, lon_e7, lat0_e7, lon0_e7):
    n = (lat_e7 - lat0_e7) * 1e-7 * 111319.5
    e = (lon_e7 - lon0_e7) * 1e-7 * 111319.5 * math.cos(math.radians(lat0_e7 * 1e-7))
    return n, e


@pytest.mark.parametrize("kind", KINDS)
def test_set_home_moves_and_locks_home_and_rtl_goes_there(kind, tmp_path):
    ap = start(kind, tmp_path, arducopter_params={"AVOID_ENABLE": 0})
    g = None
    try:
        g = Gcs(ap.pymavlink_url)
        g.streams(10)
        assert g.wait("GLOBAL_POSITION_INT", lambda p: p.lat != 0, 60.0) is not None
        end = time.monotonic() + 60.0
        first = _home(g)
        while first.latitude == 0 and time.monotonic() < end:
            g.pump(1.0)
            first = _home(g)
        lat, lon = offset_e7(first.latitude * 1e-7, first.longitude * 1e-7, 30.0, 0.0)
        alt_msl = first.altitude * 1e-3 + 5.0

        ack, sent = _set_home(g, lat_e7=lat, lon_e7=lon, alt_m=alt_msl)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, (ack, g.texts[-3:])
        assert sent is not None, "no HOME_POSITION announced with the new home"
        assert abs(sent.latitude - lat) <= _f32_e7(lat)
        assert abs(sent.longitude - lon) <= _f32_e7(lon)
        assert abs(sent.altitude * 1e-3 - alt_msl) < 0.05
        lat, lon = sent.latitude, sent.longitude

        g.pump(3.0)                                   # disarmed: a GCS's home does not follow
        held = _home(g)
        assert abs(held.latitude - lat) <= 2 and abs(held.altitude * 1e-3 - alt_msl) < 0.05

        ack, sent = _set_home(g, lat_e7=lat, lon_e7=lon, alt_m=2.0, relative=True)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, ack
        assert sent is not None and abs(sent.altitude * 1e-3 - (alt_msl + 2.0)) < 0.05
        home_alt = alt_msl + 2.0

        ack, _ = _set_home(g, lat_e7=910_000_000, lon_e7=lon, alt_m=alt_msl)
        assert ack is not None and ack.result == mav.MAV_RESULT_FAILED, ack
        assert abs(_home(g).latitude - lat) <= 2, "a refused home moved home"

        g.arm_and_takeoff(8.0)                       # 8 m above the new home
        armed_home = _home(g)
        assert abs(armed_home.latitude - lat) <= 2, "arming moved a GCS's home"
        assert abs(armed_home.altitude * 1e-3 - home_alt) < 0.05
        assert g.wait_alt(6.5, 60.0), "relative_alt never reached the take-off altitude"
        p = g.wait("GLOBAL_POSITION_INT", timeout_s=5.0)
        # relative_alt is above home; alt above sea level
        assert abs((p.alt - p.relative_alt) * 1e-3 - home_alt) < 1.0, (p.alt, p.relative_alt)

        p = g.rtl_until_landed(120.0)
        n, e = _north_east_m(p.lat, p.lon, lat, lon)
        assert math.hypot(n, e) < 5.0, f"landed {n:.1f} m N, {e:.1f} m E of the new home"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        if g is not None:
            g.close()
        ap.stop()
