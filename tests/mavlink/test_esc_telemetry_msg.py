"""ESC_TELEMETRY_1_TO_4 / _5_TO_8 as the FC's ground-station side fills them (ArduPilot's
AP_ESC_Telem units: degC, cV, cA, mAh, rpm, reports received; u16 fields clamped), checked
through pymavlink's own encode and decode."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.gcs.telemetry import ENCODERS
from silbridge.mavlink.gcs.vehicle_api import EscRow, VehicleSnapshot

ENCODE = ENCODERS[mav.MAVLINK_MSG_ID_ESC_TELEMETRY_1_TO_4]


def _roundtrip(msgs):
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    rx = mav.MAVLink(None)
    return [rx.decode(bytearray(m.pack(codec))) for m in msgs]


def test_nothing_is_sent_while_no_esc_reports():
    assert ENCODE(VehicleSnapshot(), None) == []


def test_units_clamps_and_groups_of_four():
    rows = (EscRow(0, 15.4, 16.47, 2.156, 19.2, 4846.4, 70001),
            EscRow(1, -3.0, 700.0, 800.0, 70000.0, 70000.0, 5),
            EscRow(5, 40.0, 12.0, 1.0, 3.0, 1000.0, 2))
    first, second = _roundtrip(ENCODE(VehicleSnapshot(esc=rows), None))
    assert first.get_type() == "ESC_TELEMETRY_1_TO_4"
    assert first.temperature == [15, 0, 0, 0]
    assert first.voltage == [1647, 65535, 0, 0]
    assert first.current == [216, 65535, 0, 0]
    assert first.totalcurrent == [19, 65535, 0, 0]
    assert first.rpm == [4846, 65535, 0, 0]
    assert first.count == [70001 & 0xFFFF, 5, 0, 0]
    assert second.get_type() == "ESC_TELEMETRY_5_TO_8"
    assert second.rpm == [0, 1000, 0, 0] and second.voltage == [0, 1200, 0, 0]
