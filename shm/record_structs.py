"""Struct readers of the record payloads, for hot paths that read a step's bytes directly.

A foreign autopilot's link (bridge/ardupilot_physics.py for ArduPilot's JSON reply,
mavlink/hil/px4_hil.py for PX4's HIL frames) reads a few fields of each record of a physics
step, thousands of times a second. `struct.unpack_from` on the step's bytes costs a few us
where numpy field views cost tens, so they read through these. Each skips the 24-byte header
(shm/include/sb_records.h) and reads the payload's leading fields in declaration order;
tests/mavlink/test_px4_frames.py checks every one against the dtypes of shm/records.py.
"""

from __future__ import annotations

import struct

KIND = struct.Struct("<H")                  # the header's record kind
IMU = struct.Struct("<24x6f")               # accel_frd_m_s2[3], gyro_frd_rad_s[3]
BARO = struct.Struct("<24x2f")              # pressure_pa, temperature_c
MAG = struct.Struct("<24x3f")               # field_frd_gauss[3]
GNSS = struct.Struct("<24x3i3f2H2B")        # lat_e7, lon_e7, alt_mm, vel_ned_m_s[3], eph_cm,
                                            # epv_cm, fix_type, satellites
GT_ATT = struct.Struct("<24x10f")           # q_wxyz[4], rates_frd_rad_s[3], specific_force[3]
GT_NAV = struct.Struct("<24x3d3f")          # pos_ned_m[3], vel_ned_m_s[3]
