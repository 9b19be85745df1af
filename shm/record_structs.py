"""Struct readers of the record payloads, for hot paths that read a step's bytes directly.

A foreign autopilot's link (bridge/autopilots/px4/hil_messages.py for PX4's HIL frames; the
JSON reply's Python oracle, tests/bridge/json_reply_oracle.py) reads a few fields of each
record of a physics step, thousands of times a second. `struct.unpack_from` on the step's
bytes costs a few us where numpy field views cost tens, so they read through these. Each reads the named fields
from the slot start (header skipped as padding), derived from the dtypes of shm/records.py
by `record_struct`; tests/shm/test_layout.py checks every one against the C structs.
"""

from __future__ import annotations

from silbridge.shm.records import Kind, record_struct

KIND = record_struct(Kind.NONE, ["kind"])      # the header's record kind, any kind
IMU = record_struct(Kind.IMU, ["accel_frd_m_s2", "gyro_frd_rad_s"])
BARO = record_struct(Kind.BARO, ["pressure_pa", "temperature_c"])
MAG = record_struct(Kind.MAG, ["field_frd_gauss"])
GNSS = record_struct(Kind.GNSS, ["lat_e7", "lon_e7", "alt_mm", "vel_ned_m_s", "eph_cm",
                                 "epv_cm", "fix_type", "satellites"])
GT_ATT = record_struct(Kind.GT_ATT, ["q_wxyz", "rates_frd_rad_s", "specific_force_frd_m_s2"])
GT_NAV = record_struct(Kind.GT_NAV, ["pos_ned_m", "vel_ned_m_s"])
