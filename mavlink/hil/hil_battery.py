"""The BATTERY record on the MAVLink HIL link: BATTERY_STATUS (#147) from the bridge end.

The bridge's pack (bridge/battery/) is quantised at the source to what BATTERY_STATUS
carries, so the FC end rebuilds the record bit for bit: pack voltage as whole mV per cell,
current in cA, consumption in whole mAh, state of charge in whole %, temperature in cdegC.
The record holds the pack voltage and its lowest cell, not every cell: the message shows
the lowest cell first and the others at their mean (whole mV, the remainder spread from the
second cell on), so the cells still add up to the pack and the lowest is the minimum.
Cells 1..10 ride in voltages[] (65535 = no cell), 11..14 in voltages_ext[] (0 = no cell),
as the MAVLink spec assigns them.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.shm.records import KIND_BATTERY, Kind, record_struct

ID_BATTERY_STATUS = mav.MAVLINK_MSG_ID_BATTERY_STATUS
SLOT = record_struct(Kind.BATTERY)
_NO_CELL = 65535


def cells_mv(voltage_v: float, lowest_cell_v: float, cells: int) -> list:
    """Whole-mV cells adding up to the pack, the lowest first."""
    low = round(lowest_cell_v * 1000.0)
    if cells <= 1:
        return [round(voltage_v * 1000.0)][:max(cells, 0)]
    rest = round(voltage_v * 1000.0) - low
    each, extra = divmod(rest, cells - 1)
    return [low] + [each + (1 if j < extra else 0) for j in range(cells - 1)]


def battery_frame(rec, codec) -> bytes:
    """The BATTERY_STATUS frame of one BATTERY record (a numpy BATTERY_DTYPE row)."""
    mv = cells_mv(float(rec["voltage_v"]), float(rec["lowest_cell_v"]), int(rec["cell_count"]))
    volts = (mv[:10] + [_NO_CELL] * 10)[:10]
    ext = (mv[10:14] + [0] * 4)[:4]
    return mav.MAVLink_battery_status_message(
        0, mav.MAV_BATTERY_FUNCTION_ALL, mav.MAV_BATTERY_TYPE_LIPO,
        round(float(rec["temperature_c"]) * 100.0), volts,
        round(float(rec["current_a"]) * 100.0), round(float(rec["consumed_mah"])), -1,
        round(float(rec["remaining"]) * 100.0), 0, mav.MAV_BATTERY_CHARGE_STATE_OK,
        ext).pack(codec)


def battery_record(m, seq: int, step_ns: int, wall: int) -> bytes:
    """The BATTERY record of a BATTERY_STATUS message (the inverse of battery_frame)."""
    mv = [v for v in m.voltages if v != _NO_CELL] + [v for v in m.voltages_ext if v]
    return SLOT.pack(KIND_BATTERY, 0, seq, step_ns, wall, sum(mv) / 1000.0,
                     m.current_battery / 100.0, float(m.current_consumed),
                     m.battery_remaining / 100.0, m.temperature / 100.0,
                     (min(mv) if mv else 0) / 1000.0, len(mv))
