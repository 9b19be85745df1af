"""FS_OPTIONS as ArduCopter 4.6 has it (ArduCopter/events.cpp, Parameters.cpp): which failsafes
let the flight go on, in which mode. Its default, 16, lets a pilot-flown mode go on through a
GCS failsafe; every other failsafe acts (an RC loss in AUTO or GUIDED returns home).

The answer is the text ArduCopter appends to its announcement ("Radio Failsafe - Continuing
Auto"), or None when the failsafe's action goes ahead.
"""

from __future__ import annotations

from silbridge.mavlink.gcs.vehicle_api import CopterMode as M

RC_CONTINUE_IF_AUTO = 1 << 0
GCS_CONTINUE_IF_AUTO = 1 << 1
RC_CONTINUE_IF_GUIDED = 1 << 2
CONTINUE_IF_LANDING = 1 << 3
GCS_CONTINUE_IF_PILOT_CONTROL = 1 << 4

# Modes a pilot flies (ArduCopter's !is_autopilot()); ours that are not: AUTO, GUIDED, RTL,
# LAND, CIRCLE, BRAKE, SMART_RTL.
PILOT_MODES = (M.STABILIZE, M.ACRO, M.ALT_HOLD, M.LOITER, M.POSHOLD)


def continuing(failsafe: str, mode: int, options: int) -> str | None:
    """failsafe: "Radio" or "GCS"; mode: the custom mode flying; options: FS_OPTIONS."""
    if mode == M.LAND and options & CONTINUE_IF_LANDING:
        return "Continuing Landing"
    if failsafe == "Radio":
        if mode == M.AUTO and options & RC_CONTINUE_IF_AUTO:
            return "Continuing Auto"
        if mode == M.GUIDED and options & RC_CONTINUE_IF_GUIDED:
            return "Continuing Guided Mode"
        return None
    if mode == M.AUTO and options & GCS_CONTINUE_IF_AUTO:
        return "Continuing Auto Mode"
    if mode in PILOT_MODES and options & GCS_CONTINUE_IF_PILOT_CONTROL:
        return "Continuing Pilot Control"
    return None
