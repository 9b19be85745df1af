"""Generate silbridge/magfield_grid.py: the Earth's field on a lat/lon grid, from the WMM.

The FC looks its declination up in this grid (COMPASS_AUTODEC) and the bridge builds the
world's field from it when a scenario declares none, so both sides read one table and agree.
The values come from the World Magnetic Model 2025 (NOAA/NCEI and BGS, coefficients
WMM_2025.COF) evaluated with the pygeomag package at sea level for the scenario epoch
(bridge/scenario_schema.py: 2026.0). pygeomag is needed only here, never at run time:

    .venv/bin/pip install pygeomag==1.1.0
    .venv/bin/python tools/gen_magfield_grid.py            # writes silbridge/magfield_grid.py
    .venv/bin/python tools/gen_magfield_grid.py --check    # interpolation error vs the model

--check evaluates the committed grid (through silbridge.magfield, as the FC and the bridge
do) against the exact model midway between grid lines, where bilinear interpolation is
worst, and prints the largest and RMS errors over the inhabited latitudes.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "silbridge" / "magfield_grid.py"
COEFFICIENTS = "wmm/WMM_2025.COF"
EPOCH = 2026.0           # decimal year; the scenarios' epoch (bridge/scenario_schema.py)
STEP_DEG = 5.0
INHABITED = (-60.0, 72.0)   # latitudes of the --check figures (Ushuaia .. Tromso and beyond)


def _model():
    try:
        from pygeomag import GeoMag
    except ImportError:
        sys.exit("this tool needs pygeomag: .venv/bin/pip install pygeomag==1.1.0")
    return GeoMag(coefficients_file=COEFFICIENTS)


def _exact(model, lat_deg: float, lon_deg: float) -> tuple[float, float, float]:
    """(declination deg, inclination deg, intensity gauss) at sea level."""
    r = model.calculate(glat=lat_deg, glon=lon_deg, alt=0.0, time=EPOCH)
    return r.d, r.i, r.f * 1e-5          # pygeomag gives nT; 1 gauss = 1e5 nT


def _rows(values, fmt: str) -> str:
    """One tuple per latitude, wrapped at 100 columns."""
    import textwrap
    return "\n".join(textwrap.fill(", ".join(fmt % v for v in row), width=94,
                                    initial_indent="    (", subsequent_indent="     ") + "),"
                      for row in values)


def generate(step_deg: float) -> str:
    model = _model()
    lats = [-90.0 + i * step_deg for i in range(int(round(180 / step_deg)) + 1)]
    lons = [-180.0 + j * step_deg for j in range(int(round(360 / step_deg)) + 1)]
    dec, inc, tot = [], [], []
    for lat in lats:
        cells = [_exact(model, lat, lon) for lon in lons]
        dec.append([c[0] for c in cells])
        inc.append([c[1] for c in cells])
        tot.append([c[2] for c in cells])
    from pygeomag import __version__ as pygeomag_version
    return f'''"""The Earth's field on a {step_deg:g} x {step_deg:g} deg grid (generated: do not edit).

Written by tools/gen_magfield_grid.py from the World Magnetic Model 2025 (WMM2025, NOAA/NCEI
and BGS, coefficients WMM_2025.COF, evaluated with pygeomag {pygeomag_version}) at sea level
for epoch {EPOCH:.1f}. Rows are latitudes from LAT0_DEG northwards, columns longitudes from LON0_DEG
eastwards, STEP_DEG apart (the last column repeats the first, at +180 deg). Read it through
silbridge.magfield, which interpolates.
"""

MODEL = "WMM2025"
EPOCH = {EPOCH!r}
STEP_DEG = {step_deg!r}
LAT0_DEG = {lats[0]!r}
LON0_DEG = {lons[0]!r}

# declination, deg (east of true north positive)
DECLINATION_DEG = (
{_rows(dec, "%.2f")}
)

# inclination, deg (down positive)
INCLINATION_DEG = (
{_rows(inc, "%.2f")}
)

# total intensity, gauss
INTENSITY_GAUSS = (
{_rows(tot, "%.5f")}
)
'''


def check() -> None:
    from silbridge.magfield import field_at          # as the FC and the bridge read it
    from silbridge.magfield_grid import STEP_DEG as s
    model = _model()
    half = s / 2.0
    worst = {"dec": (0.0, None), "inc": (0.0, None), "tot": (0.0, None), "dir": (0.0, None)}
    sq = {k: 0.0 for k in worst}
    n = 0
    lat = -90.0 + half
    while lat < 90.0:
        if INHABITED[0] <= lat <= INHABITED[1]:
            lon = -180.0 + half
            while lon < 180.0:
                d, i, f = _exact(model, lat, lon)
                g = field_at(lat, lon)
                errs = {"dec": abs((g.declination_deg - d + 180.0) % 360.0 - 180.0),
                        "inc": abs(g.inclination_deg - i),
                        "tot": abs(g.intensity_gauss - f) / f * 100.0,
                        "dir": _angle_deg(g.ned_gauss, _ned(d, i, f))}
                for k, e in errs.items():
                    sq[k] += e * e
                    if e > worst[k][0]:
                        worst[k] = (e, (lat, lon))
                n += 1
                lon += s
        lat += s
    units = {"dec": "deg", "inc": "deg", "tot": "%", "dir": "deg (field direction)"}
    print(f"grid {s:g} deg, {n} cell centres, latitudes {INHABITED[0]:g}..{INHABITED[1]:g}")
    for k in worst:
        e, where = worst[k]
        print(f"  {k}: max {e:.3f} {units[k]} at {where}, RMS {math.sqrt(sq[k] / n):.3f}")


def _ned(dec_deg, inc_deg, tot):
    d, i = math.radians(dec_deg), math.radians(inc_deg)
    h = tot * math.cos(i)
    return (h * math.cos(d), h * math.sin(d), tot * math.sin(i))


def _angle_deg(a, b) -> float:
    dot = sum(x * y for x, y in zip(a, b))
    na = math.sqrt(sum(x * x for x in a))
    nb = math.sqrt(sum(x * x for x in b))
    return math.degrees(math.acos(max(-1.0, min(1.0, dot / (na * nb)))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=STEP_DEG, help="grid spacing, deg")
    ap.add_argument("--check", action="store_true",
                    help="print the committed grid's interpolation error instead of writing")
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args(argv)
    if a.check:
        check()
        return 0
    a.out.write_text(generate(a.step))
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
