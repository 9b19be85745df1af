"""The value grids MAVLink HIL messages carry exactly, for quantising at the source.

A closed loop gives the same trajectory over shared memory and over MAVLink HIL only if the
flight controller reads the same numbers either way. Where a HIL field is coarser than the
record field, the bridge's sensor models round their output onto the grid the message can
carry (always, whatever the transport), so the record and the decoded message are bit for bit
the same float. Each function returns a value `hil_codec` encodes and decodes without loss:

- barometric pressure: HIL_SENSOR.abs_pressure is float32 hPa and the record float32 Pa. On a
  grid of 17 significant bits in hPa (1/128 hPa = 0.78 Pa near sea level, about a third of a
  typical barometer's noise) both hPa and hPa * 100 are exact float32 numbers (17 bits times
  100 < 2^24), so Pa -> hPa -> Pa returns the same float32.
- velocities: HIL_GPS and HIL_STATE_QUATERNION carry int16 cm/s: whole cm/s.
- height: HIL_STATE_QUATERNION.alt is int32 mm: whole mm of the NED down position.
"""

from __future__ import annotations

import math

# HIL_SENSOR pressure: 17 significant bits in hPa (see the module docstring).
_PRESSURE_BITS = 17


def pressure_pa(pa: float) -> float:
    """Pa on the grid HIL_SENSOR.abs_pressure (float32 hPa) carries exactly."""
    if not (pa > 0.0) or math.isinf(pa):
        return pa
    hpa = pa / 100.0
    _, exp2 = math.frexp(hpa)                 # hpa = m * 2**exp2, 0.5 <= m < 1
    quantum = math.ldexp(1.0, exp2 - _PRESSURE_BITS)
    return round(hpa / quantum) * quantum * 100.0


def velocity_m_s(v: float) -> float:
    """Whole cm/s, as HIL_GPS / HIL_STATE_QUATERNION int16 fields carry it."""
    if v != v:
        return v
    cm = max(-32767, min(32767, round(v * 100.0)))
    return cm / 100.0


def down_m(d: float) -> float:
    """Whole mm, as HIL_STATE_QUATERNION.alt (int32 mm) carries a height."""
    if d != d:
        return d
    return round(d * 1000.0) / 1000.0
