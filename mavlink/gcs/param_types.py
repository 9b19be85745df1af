"""MAV_PARAM_TYPE rules shared by the PARAM_* protocol and the .parm loader.

ArduPilot's encoding: every value travels as a float32; integer parameters are C-cast to float
and reported with their integer type, so a GCS knows to show (and MAVSDK to accept) an integer.
An incoming value for an integer parameter is rounded to the nearest integer and must fit the
type; a NaN or infinity is refused for every type.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mav

INT_RANGES = {
    mav.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1),
    mav.MAV_PARAM_TYPE_INT8: (-2**7, 2**7 - 1),
    mav.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1),
    mav.MAV_PARAM_TYPE_INT16: (-2**15, 2**15 - 1),
    mav.MAV_PARAM_TYPE_UINT32: (0, 2**32 - 1),
    mav.MAV_PARAM_TYPE_INT32: (-2**31, 2**31 - 1),
    mav.MAV_PARAM_TYPE_UINT64: (0, 2**64 - 1),
    mav.MAV_PARAM_TYPE_INT64: (-2**63, 2**63 - 1),
}
INT_TYPES = frozenset(INT_RANGES)
TYPE_NAMES = {v: k.replace("MAV_PARAM_TYPE_", "") for k, v in vars(mav).items()
              if k.startswith("MAV_PARAM_TYPE_") and k != "MAV_PARAM_TYPE_ENUM_END"}


def coerce(value: float, param_type: int) -> tuple[float | int | None, str | None]:
    """(value the store should get, None) or (None, reason it cannot be stored)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None, f"value {value!r} is not a number"
    if not math.isfinite(v):
        return None, f"value {v} not finite"
    if param_type in INT_RANGES:
        iv = int(round(v))
        lo, hi = INT_RANGES[param_type]
        if not lo <= iv <= hi:
            return None, f"{v:g} not in {TYPE_NAMES.get(param_type, param_type)} range"
        return iv, None
    return v, None


def wire_value(value: float | int) -> float:
    """The float a PARAM_VALUE carries (ArduPilot C-cast for integers)."""
    return float(value)
