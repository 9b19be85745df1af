"""The failsafe settings every autopilot flies F1..F12 with, set equal where their defaults
differ, and said so on the report page (`describe()`).

- Ground-station loss: RTL after 5 s of silence (sim time for all three). ArduCopter's and our
  FC's FS_GCS_ENABLE default to 0 (off); PX4's NAV_DLL_ACT to 0 (off) with COM_DL_LOSS_T 10 s.
- Battery: the low level at 3.5 V per cell of the physics side's 4S pack (14.0 V, held 10 s),
  action RTL (ArduCopter's BATT_FS_LOW_ACT defaults to 0, warn only). PX4 judges the
  remaining charge, not the voltage: its critical level is put where 3.5 V per cell sits on
  its linear 3.3..4.2 V scale (0.22), and COM_LOW_BAT_ACT 3 returns there.
- EKF failsafe: ArduCopter's defaults (FS_EKF_ACTION 1 = LAND, FS_EKF_THRESH 0.8) for
  ArduCopter and ours; PX4's position-loss failsafe is its own (no equivalent threshold).
- RC loss (F11): ArduCopter 4.6's defaults for ArduCopter and ours, written out: FS_THR_ENABLE
  1 (RTL, LAND without a position) and FS_OPTIONS 16 (no "continue in AUTO / GUIDED" bit, so
  the radio failsafe acts in the mission; bit 4 only lets pilot-flown modes go on through a
  GCS failsafe). RC_FS_TIMEOUT 1 s is both their default. PX4 has no RC here (translate.py).
- Crash (F12): FS_CRASH_CHECK 1, ArduCopter's default and ours; PX4's failure detector with
  its defaults (FD_FAIL_P / FD_FAIL_R 60 deg).
- Return altitude 15 m and cruise speed 5 m/s for all three (PX4 defaults: 60 m return,
  5 m/s; ArduCopter: 15 m, 10 m/s).
"""

from __future__ import annotations

CELLS = 4
LOW_V_PER_CELL = 3.5
EMPTY_V_PER_CELL, FULL_V_PER_CELL = 3.3, 4.2     # PX4's linear scale (our pack's open circuit)
LOW_VOLT = CELLS * LOW_V_PER_CELL
GCS_TIMEOUT_S = 5.0

ARDUCOPTER = {
    "FS_GCS_ENABLE": 1, "FS_GCS_TIMEOUT": GCS_TIMEOUT_S,
    "FS_THR_ENABLE": 1, "FS_OPTIONS": 16, "FS_CRASH_CHECK": 1,
    "FS_EKF_ACTION": 1, "FS_EKF_THRESH": 0.8,
    "BATT_MONITOR": 4, "BATT_LOW_VOLT": LOW_VOLT, "BATT_CRT_VOLT": 0.0,
    "BATT_FS_LOW_ACT": 2, "BATT_LOW_TIMER": 10,
    "RTL_ALT": 1500, "WPNAV_SPEED": 500.0,
}
OURS = {
    "FS_GCS_ENABLE": 1, "FS_GCS_TIMEOUT": GCS_TIMEOUT_S,
    "FS_THR_ENABLE": 1, "FS_OPTIONS": 16, "FS_CRASH_CHECK": 1,
    "BATT_LOW_VOLT": LOW_VOLT, "BATT_CRT_VOLT": 0.0, "BATT_FS_LOW_ACT": 2, "BATT_LOW_TIMER": 10,
    "RTL_ALT": 1500, "WPNAV_SPEED": 500.0,
}
_CRIT = round((LOW_V_PER_CELL - EMPTY_V_PER_CELL) / (FULL_V_PER_CELL - EMPTY_V_PER_CELL), 3)
PX4 = {
    "NAV_DLL_ACT": 2, "COM_DL_LOSS_T": GCS_TIMEOUT_S,
    "BAT1_N_CELLS": CELLS, "BAT1_V_EMPTY": EMPTY_V_PER_CELL, "BAT1_V_CHARGED": FULL_V_PER_CELL,
    "BAT_LOW_THR": round(_CRIT + 0.05, 3), "BAT_CRIT_THR": _CRIT, "COM_LOW_BAT_ACT": 3,
    "RTL_RETURN_ALT": 15.0, "RTL_DESCEND_ALT": 10.0, "MPC_XY_CRUISE": 5.0,
}
SETTINGS = {"ours": OURS, "ardupilot": ARDUCOPTER, "px4": PX4}


def describe() -> str:
    """The settings as the report lists them."""
    return "\n".join(f"- {name}: " + ", ".join(f"{k} {v:g}" for k, v in s.items())
                     for name, s in (("ours", OURS), ("ArduCopter", ARDUCOPTER),
                                     ("PX4", PX4)))
