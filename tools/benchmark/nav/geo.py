"""Local north/east metres about home <-> latitude/longitude, exactly as the bridge's ground
truth measures them (bridge/fdm.py: WGS-84 meridian and prime-vertical radii at home).

A target sent to an autopilot as latitude/longitude then lies at its planned NE offset in the
ground-truth frame the scores are computed in, whatever flat-earth approximation the
autopilot uses inside: its GNSS comes from the same truth, so its own conversion cancels.
"""

from __future__ import annotations

import math

WGS84_A_M = 6378137.0        # semi-major axis (bridge/fdm.py)
WGS84_E2 = 6.69437999014e-3  # first eccentricity squared (bridge/fdm.py)


def radii_m(lat_deg: float) -> tuple[float, float]:
    """(metres per radian of latitude, of longitude) at lat_deg."""
    s = math.sin(math.radians(lat_deg))
    w = math.sqrt(1.0 - WGS84_E2 * s * s)
    return (WGS84_A_M * (1.0 - WGS84_E2) / (w * w * w),
            WGS84_A_M / w * math.cos(math.radians(lat_deg)))


def ne_to_latlon_e7(home_lat_deg: float, home_lon_deg: float, north_m: float,
                    east_m: float) -> tuple[int, int]:
    """MAVLink's degE7 latitude and longitude of a point north_m, east_m from home."""
    r_lat, r_lon = radii_m(home_lat_deg)
    lat = home_lat_deg + math.degrees(north_m / r_lat)
    lon = home_lon_deg + math.degrees(east_m / r_lon)
    return int(round(lat * 1e7)), int(round(lon * 1e7))


def latlon_e7_to_ne(home_lat_deg: float, home_lon_deg: float, lat_e7: int,
                    lon_e7: int) -> tuple[float, float]:
    """The inverse of ne_to_latlon_e7: (north_m, east_m) of a reported position."""
    r_lat, r_lon = radii_m(home_lat_deg)
    return (math.radians(lat_e7 * 1e-7 - home_lat_deg) * r_lat,
            math.radians(lon_e7 * 1e-7 - home_lon_deg) * r_lon)
