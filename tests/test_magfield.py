"""The WMM grid lookup (silbridge/magfield.py) that the FC's COMPASS_AUTODEC and the bridge's
default field both read.

Reference values: the World Magnetic Model 2025 (WMM_2025.COF) evaluated with pygeomag 1.1.0
at sea level for 2026.0 (the grid's model and epoch), computed once while writing this test:
    GeoMag(coefficients_file="wmm/WMM_2025.COF").calculate(glat, glon, alt=0.0, time=2026.0)
The tolerances are the 5-deg grid's interpolation error at these places (the grid's own
figures: tools/gen_magfield_grid.py --check).
"""

from __future__ import annotations

import math

import pytest

from silbridge.magfield import field_at

# name, lat deg, lon deg, declination deg, inclination deg, intensity gauss (WMM2025, 2026.0)
WMM2025 = [
    ("Zurich", 47.397742, 8.545594, 3.55, 63.52, 0.4837),
    ("Canberra", -35.363261, 149.16523, 12.67, -66.05, 0.5810),
    ("Seattle", 47.6062, -122.3321, 14.97, 68.78, 0.5268),
    ("Sao Paulo", -23.5505, -46.6333, -21.85, -40.65, 0.2280),   # South Atlantic Anomaly
    ("Tokyo", 35.6762, 139.6503, -7.91, 49.53, 0.4687),
    ("Cape Town", -33.9249, 18.4241, -26.62, -64.71, 0.2501),
    ("Reykjavik", 64.1466, -21.9426, -11.28, 75.43, 0.5258),
]


@pytest.mark.parametrize("name, lat, lon, dec, inc, total", WMM2025, ids=[r[0] for r in WMM2025])
def test_the_grid_gives_the_wmm_field(name, lat, lon, dec, inc, total):
    f = field_at(lat, lon)
    assert f.declination_deg == pytest.approx(dec, abs=0.25)
    assert f.inclination_deg == pytest.approx(inc, abs=0.2)
    assert f.intensity_gauss == pytest.approx(total, rel=0.005)
    assert f.declination_rad == pytest.approx(math.radians(f.declination_deg))


def test_the_ned_vector_carries_the_same_declination_inclination_and_intensity():
    f = field_at(-35.363261, 149.16523)
    n, e, d = f.ned_gauss
    assert math.degrees(math.atan2(e, n)) == pytest.approx(f.declination_deg, abs=1e-9)
    assert math.degrees(math.atan2(d, math.hypot(n, e))) == pytest.approx(f.inclination_deg,
                                                                          abs=1e-9)
    assert math.sqrt(n * n + e * e + d * d) == pytest.approx(f.intensity_gauss, rel=1e-12)
    assert d < 0          # southern hemisphere: the field points up


def test_longitude_wraps_and_the_antimeridian_is_continuous():
    assert field_at(10.0, 190.0) == field_at(10.0, -170.0)
    west, east = field_at(-20.0, 179.999), field_at(-20.0, -179.999)
    assert west.declination_deg == pytest.approx(east.declination_deg, abs=0.01)
    assert west.intensity_gauss == pytest.approx(east.intensity_gauss, rel=1e-4)


def test_declination_interpolates_across_the_plus_minus_180_jump():
    # Antarctica south of the magnetic pole: the grid cell's corners read -173.84, 178.62,
    # -177.17 and 172.12 deg, i.e. all nearly south. A plain average would say about 0
    # (north); WMM2025 at -77.5, 142.5 for 2026.0 says -179.57 (pygeomag, as above).
    f = field_at(-77.5, 142.5)
    assert abs((f.declination_deg - -179.57 + 180.0) % 360.0 - 180.0) < 1.0
    assert -180.0 <= f.declination_deg < 180.0


def test_a_latitude_beyond_the_poles_is_refused():
    with pytest.raises(ValueError, match="latitude"):
        field_at(91.0, 0.0)
    with pytest.raises(ValueError):
        field_at(float("nan"), 0.0)
