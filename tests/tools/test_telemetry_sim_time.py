"""Telemetry paced on simulated time, as ArduCopter SITL paces it: a script at 5x real time
that asks for GLOBAL_POSITION_INT at 10 Hz gets 10 per simulated second (50 per wall second),
with SET_MESSAGE_INTERVAL and with REQUEST_DATA_STREAM; HEARTBEAT comes once per simulated
second; SYSTEM_TIME's Unix time advances with time_boot_ms. The same client runs against
silbridge (`fly --speed 5`) and, with SILBRIDGE_ARDUCOPTER set, the real ArduCopter 4.6 at
--speedup 5 (measured there: 10.0 per sim s, HEARTBEAT 1.0 per sim s, Unix time at 5x).

Rates are counted over the time_boot_ms span of several simulated seconds, never against the
wall clock: a loaded machine that slows the simulation changes nothing here, whereas pacing on
the wall clock would give 2 per simulated second at 5x.
"""

from __future__ import annotations

import os
import sys

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

sys.path.insert(0, os.path.dirname(__file__))

from autopilots import KINDS, ArduCopter, Silbridge, skip_without_arducopter  # noqa: E402
from gcs_session import Gcs  # noqa: E402

SPEED = 5.0
ASKED_HZ = 10
MIN_SPAN_S = 8.0        # simulated seconds of GLOBAL_POSITION_INT counted


def _start(kind: str, tmp_path):
    skip_without_arducopter(kind)
    if kind == "silbridge":
        return Silbridge(speed=SPEED, cwd=str(tmp_path))
    return ArduCopter(str(tmp_path / "arducopter"), speedup=SPEED)


def _collect_sim_seconds(gcs: Gcs, span_s: float, timeout_s: float = 60.0) -> list:
    """Messages until GLOBAL_POSITION_INT has covered span_s of time_boot_ms."""
    got, first = [], None
    for _ in range(int(timeout_s / 0.5)):
        for m in gcs.collect(0.5):
            got.append(m)
            if m.get_type() == "GLOBAL_POSITION_INT":
                first = m.time_boot_ms if first is None else first
                if m.time_boot_ms - first >= span_s * 1000:
                    return got
    raise AssertionError(f"GLOBAL_POSITION_INT did not cover {span_s} s of sim time")


@pytest.mark.parametrize("how", ("set_message_interval", "request_data_stream"))
@pytest.mark.parametrize("kind", KINDS)
def test_rates_per_simulated_second(kind, how, tmp_path):
    ap = _start(kind, tmp_path)
    try:
        gcs = Gcs(ap.pymavlink_url, timeout_s=60.0)
        if how == "set_message_interval":
            ack = gcs.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL,
                              mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 1e6 / ASKED_HZ)
            assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, ack
        else:
            gcs.m.mav.request_data_stream_send(1, 1, mav.MAV_DATA_STREAM_POSITION, ASKED_HZ, 1)
        ack = gcs.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, mav.MAVLINK_MSG_ID_SYSTEM_TIME,
                          500_000)
        assert ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, ack
        gcs.collect(1.0)            # the new rates settle
        got = _collect_sim_seconds(gcs, MIN_SPAN_S)

        pos = [m.time_boot_ms for m in got if m.get_type() == "GLOBAL_POSITION_INT"]
        span_s = (pos[-1] - pos[0]) / 1000.0
        hz = (len(pos) - 1) / span_s
        assert 0.8 * ASKED_HZ <= hz <= 1.2 * ASKED_HZ, \
            f"GLOBAL_POSITION_INT {hz:.2f} per simulated second, asked {ASKED_HZ}"
        assert all(b > a for a, b in zip(pos, pos[1:])), "time_boot_ms not increasing"

        # HEARTBEAT on the same clock: once per simulated second of the window
        hb = [m for m in got if m.get_type() == "HEARTBEAT" and m.get_srcSystem() == 1
              and m.get_srcComponent() == 1]
        stamped = [m.time_boot_ms for m in got if hasattr(m, "time_boot_ms")]
        window_s = (max(stamped) - min(stamped)) / 1000.0
        assert 0.7 <= len(hb) / window_s <= 1.3, \
            f"{len(hb)} HEARTBEATs in {window_s:.1f} simulated seconds"

        # SYSTEM_TIME: Unix time advances with time_boot_ms (ArduCopter: 0 until GPS time)
        st = [m for m in got if m.get_type() == "SYSTEM_TIME" and m.time_unix_usec > 0]
        assert len(st) >= 4, f"{len(st)} SYSTEM_TIME with a Unix time"
        ratio = ((st[-1].time_unix_usec - st[0].time_unix_usec) / 1000.0
                 / (st[-1].time_boot_ms - st[0].time_boot_ms))
        assert 0.95 <= ratio <= 1.05, f"Unix time runs at {ratio:.2f}x time_boot_ms"
    except AssertionError as exc:
        raise AssertionError(f"{kind}: {exc}\nautopilot said:\n{ap.stop()[-2500:]}") from None
    finally:
        ap.stop()
