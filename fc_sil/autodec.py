"""COMPASS_AUTODEC: the declination looked up at the vehicle's position, as ArduCopter does.

ArduCopter (AP_Compass, COMPASS_AUTODEC = 1 by default) sets COMPASS_DEC from its WMM table
once it knows where it is; it sets the parameter's value without saving it. Without this,
a zero COMPASS_DEC makes the heading estimate off by the declination (3.5 deg at the default
home). The table is silbridge/magfield.py, the one the bridge builds the world's field from.

Both supervisors use it: the MAVLink vehicle (vehicle.py) at its estimator origin, and the
scenario's AutoFlight (autoflight.py) at its first 3D fix.
"""

from __future__ import annotations

from silbridge.magfield import field_at


class AutoDeclination:
    """Decides when COMPASS_DEC is due: at the first position, and again if it moves."""

    def __init__(self):
        self._at: tuple[int, int] | None = None     # (lat_e7, lon_e7) last looked up

    def due(self, enabled: float, lat_e7: int, lon_e7: int) -> float | None:
        """The declination (rad) to set as COMPASS_DEC now, or None (off, or already set)."""
        if not enabled or (lat_e7, lon_e7) == self._at:
            return None
        self._at = (lat_e7, lon_e7)
        return field_at(lat_e7 * 1e-7, lon_e7 * 1e-7).declination_rad
