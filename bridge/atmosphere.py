"""International Standard Atmosphere (troposphere), the reference for the baro model.

JSBSim computes the same standard atmosphere (atmosphere/P-psf); this closed
form lets tests and tools check a pressure without JSBSim. ICAO Doc 7488:
p0 = 101325 Pa, T0 = 288.15 K, lapse 0.0065 K/m, g0 = 9.80665 m/s^2,
R = 287.05287 J/(kg K) (dry air), valid below 11 km geopotential altitude.
"""

from __future__ import annotations

P0_PA = 101325.0
T0_K = 288.15
LAPSE_K_M = 0.0065
R_AIR = 287.05287
G0 = 9.80665
EARTH_RADIUS_M = 6356766.0  # ICAO radius for geometric -> geopotential altitude


def geopotential_m(geometric_alt_m: float) -> float:
    return EARTH_RADIUS_M * geometric_alt_m / (EARTH_RADIUS_M + geometric_alt_m)


def isa_pressure_pa(alt_msl_m: float) -> float:
    """ISA static pressure at a geometric altitude above MSL (below 11 km)."""
    h = geopotential_m(alt_msl_m)
    return P0_PA * (1.0 - LAPSE_K_M * h / T0_K) ** (G0 / (R_AIR * LAPSE_K_M))


def isa_temperature_k(alt_msl_m: float) -> float:
    return T0_K - LAPSE_K_M * geopotential_m(alt_msl_m)
