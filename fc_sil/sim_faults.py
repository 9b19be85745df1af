"""ArduPilot's SIM_* fault parameters on our FC, for MAVProxy users: each group -> a catalog fault.

ArduCopter SITL users inject faults by setting SIM_* parameters (`param set SIM_GPS_DISABLE 1`).
Our FC declares the ones whose fault the catalog (shm/fault_catalog.py) carries cleanly, with
ArduCopter 4.6.0's exact names, types and defaults (read from the real binary's parameter
list; meanings from ArduPilot's libraries/SITL/SITL.cpp and SIM_GPS.cpp). Setting one switches
its catalog fault on; setting it back to its default (every parameter of the group at its
default) switches it off. Values are converted to the catalog's units here, once:

  SIM_GPS_DISABLE 1                 gnss off
  SIM_GPS_GLITCH_X/Y/Z              gnss glitch; X/Y are latitude/longitude offsets in degrees
                                    (as ArduPilot adds them to the fix), Z metres up; converted
                                    to metres north/east/down at the latitude of the FC's fix
                                    when the parameter is set
  SIM_GPS_NUMSATS (10)              gnss sats_drop to that count at once (ramp 0 s)
  SIM_GPS_VERR_X/Y/Z                gnss vel_error, m/s NED
  SIM_BARO_DRIFT                    baro drift, m/s (positive: reads higher)
  SIM_BARO_GLITCH                   baro glitch, m
  SIM_BARO_FREEZE 1                 baro stuck
  SIM_MAG1_FAIL 1                   mag off
  SIM_MAG_MOT_X/Y/Z                 mag motor_interference, mGauss/A -> gauss/A
  SIM_ENGINE_MUL < 1, SIM_ENGINE_FAIL   motor thrust_loss of servo ENGINE_FAIL (0-based, so
                                    motor ENGINE_FAIL + 1), remaining = ENGINE_MUL
  SIM_RC_FAIL 1                     rc lost (no pulses; 2, "neutral sticks", is not modelled)
  SB_SIM_GCS_FAIL 1                 gcs lost (ours: ArduPilot has no GCS-loss parameter); the
                                    way a scenario's [[failure]] unit "gcs" reaches the FC
  SIM_GYR_FAIL_MSK / SIM_ACC_FAIL_MSK bit 0   gyro / accel stuck (ArduPilot freezes the
                                    sensor; we have one IMU, so bits 1-2 have nothing to act on)
  SIM_GYR1_BIAS_X/Y/Z, SIM_ACC1_BIAS_X/Y/Z    gyro bias rad/s, accel bias m/s^2, body FRD

Left out because the catalog has no clean counterpart: SIM_BARO_DISABLE (no baro off),
SIM_GPS_DRIFTALT (altitude-only drift), SIM_GPS_JAM, SIM_ACCELn_FAIL (a fixed value).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

# Metres per degree of latitude on ArduPilot's sphere (LATLON_TO_M, radius 6378100 m).
M_PER_DEG = 6378100.0 * math.pi / 180.0
GPS_NUMSATS_DEFAULT = 10


@dataclass(frozen=True)
class SimFault:
    """One group of SIM_* parameters and the catalog fault it describes."""

    names: tuple[str, ...]
    # values (name -> value), latitude deg -> [(unit, type, instance, params)] wanted on
    build: Callable[[dict, float], list]


def _vec(v: dict, prefix: str) -> tuple[float, float, float]:
    return (v[prefix + "X"], v[prefix + "Y"], v[prefix + "Z"])


def _gps_glitch(v: dict, lat_deg: float) -> list:
    x, y, z = _vec(v, "SIM_GPS_GLITCH_")
    if x == y == z == 0.0:
        return []
    off = (x * M_PER_DEG, y * M_PER_DEG * math.cos(math.radians(lat_deg)), -z)
    return [("gnss", "glitch", 1, {"offset_m": off})]


def _gps_verr(v: dict, lat_deg: float) -> list:
    e = _vec(v, "SIM_GPS_VERR_")
    return [] if e == (0.0, 0.0, 0.0) else [("gnss", "vel_error", 1, {"error_m_s": e})]


def _mag_mot(v: dict, lat_deg: float) -> list:
    m = _vec(v, "SIM_MAG_MOT_")
    if m == (0.0, 0.0, 0.0):
        return []
    return [("mag", "motor_interference", 1, {"gauss_per_a": tuple(c * 1e-3 for c in m)})]


def _engine(v: dict, lat_deg: float) -> list:
    mul, servo = v["SIM_ENGINE_MUL"], int(v["SIM_ENGINE_FAIL"])
    if mul >= 1.0:
        return []
    return [("motor", "thrust_loss", servo + 1, {"remaining": max(0.0, mul)})]


def _bias(unit: str, names: tuple[str, str, str]) -> SimFault:
    prefix = names[0][:-1]      # "SIM_GYR1_BIAS_"

    def build(v: dict, lat_deg: float) -> list:
        b = _vec(v, prefix)
        return [] if b == (0.0, 0.0, 0.0) else [(unit, "bias", 1, {"bias": b})]
    return SimFault(names, build)


def _scalar(name: str, unit: str, ftype: str, param: str) -> SimFault:
    """A value that is the fault's one parameter; 0 (its default) means no fault."""
    def build(v: dict, lat_deg: float) -> list:
        return [] if v[name] == 0.0 else [(unit, ftype, 1, {param: v[name]})]
    return SimFault((name,), build)


def _numsats(v: dict, lat_deg: float) -> list:
    n = int(v["SIM_GPS_NUMSATS"])
    if n == GPS_NUMSATS_DEFAULT:
        return []
    return [("gnss", "sats_drop", 1, {"satellites": n, "ramp_s": 0.0})]


def _flag(name: str, unit: str, ftype: str, params: dict | None = None, bit: int | None = None):
    def build(v: dict, lat_deg: float) -> list:
        x = int(v[name])
        on = bool(x & (1 << bit)) if bit is not None else x == 1
        return [(unit, ftype, 1, dict(params or {}))] if on else []
    return SimFault((name,), build)


TABLE: tuple[SimFault, ...] = (
    _flag("SIM_GPS_DISABLE", "gnss", "off"),
    SimFault(("SIM_GPS_GLITCH_X", "SIM_GPS_GLITCH_Y", "SIM_GPS_GLITCH_Z"), _gps_glitch),
    SimFault(("SIM_GPS_NUMSATS",), _numsats),
    SimFault(("SIM_GPS_VERR_X", "SIM_GPS_VERR_Y", "SIM_GPS_VERR_Z"), _gps_verr),
    _scalar("SIM_BARO_DRIFT", "baro", "drift", "rate_m_s"),
    _scalar("SIM_BARO_GLITCH", "baro", "glitch", "offset_m"),
    _flag("SIM_BARO_FREEZE", "baro", "stuck"),
    _flag("SIM_MAG1_FAIL", "mag", "off"),
    SimFault(("SIM_MAG_MOT_X", "SIM_MAG_MOT_Y", "SIM_MAG_MOT_Z"), _mag_mot),
    SimFault(("SIM_ENGINE_MUL", "SIM_ENGINE_FAIL"), _engine),
    _flag("SIM_RC_FAIL", "rc", "lost"),
    _flag("SB_SIM_GCS_FAIL", "gcs", "lost"),
    _flag("SIM_GYR_FAIL_MSK", "gyro", "stuck", {"axis": 0}, bit=0),
    _flag("SIM_ACC_FAIL_MSK", "accel", "stuck", {"axis": 0}, bit=0),
    _bias("gyro", ("SIM_GYR1_BIAS_X", "SIM_GYR1_BIAS_Y", "SIM_GYR1_BIAS_Z")),
    _bias("accel", ("SIM_ACC1_BIAS_X", "SIM_ACC1_BIAS_Y", "SIM_ACC1_BIAS_Z")),
)

NAMES: tuple[str, ...] = tuple(n for f in TABLE for n in f.names)


def wanted(get: Callable[[str], float], lat_deg: float) -> dict:
    """(unit, type, instance) -> params of every fault the SIM_* values ask for now."""
    out = {}
    for f in TABLE:
        values = {n: float(get(n)) for n in f.names}
        for unit, ftype, instance, params in f.build(values, lat_deg):
            out[(unit, ftype, instance)] = params
    return out
