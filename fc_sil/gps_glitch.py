"""GPS glitch messages: ArduCopter's gpsglitch_check (ArduCopter/events.cpp).

The estimator's gps_glitching state (innov_ratios.py: the GNSS innovations failed their gate
for 1 s; clear after 10 s of passing) is announced when it changes, both at CRITICAL:
"GPS Glitch or Compass error" and "Glitch cleared". The rejection itself happens in the
gate (gnss_gate.py); this only tells the pilot.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav


class GpsGlitchCheck:
    def __init__(self):
        self.glitching = False

    def check(self, v, ratios) -> None:
        if ratios.gps_glitching == self.glitching:
            return
        self.glitching = ratios.gps_glitching
        v.statustext(mav.MAV_SEVERITY_CRITICAL,
                     "GPS Glitch or Compass error" if self.glitching else "Glitch cleared")
