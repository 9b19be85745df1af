"""QGC WPL 110 mission files (the plain-text format of MAVProxy and Mission Planner).

    QGC WPL 110
    0	1	0	16	0	0	0	0	-35.3632621	149.1652374	584.09	1
    seq current frame command p1 p2 p3 p4 x/lat y/lon z/alt autocontinue (tab separated)

Latitude and longitude are degrees in the file and degrees*1e7 in a MissionItem (global
frames); they are written with 8 decimals so the integer comes back exactly. Other values are
written with Python's shortest round-trip form, so save-then-load gives the same items.
"""

from __future__ import annotations

import math
import os

from silbridge.mavlink.atomic_file import write_text_atomic
from silbridge.mavlink.errors import MissionFileError
from silbridge.mavlink.gcs.mission_store import GLOBAL_FRAMES
from silbridge.mavlink.gcs.vehicle_api import MissionItem

HEADER = "QGC WPL 110"


def _num(v: float) -> str:
    if math.isfinite(v) and v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(float(v))


def format_wpl(items: list[MissionItem] | tuple[MissionItem, ...]) -> str:
    lines = [HEADER]
    for it in items:
        if it.frame in GLOBAL_FRAMES:
            x, y = f"{it.x / 1e7:.8f}", f"{it.y / 1e7:.8f}"
        else:
            x, y = str(it.x), str(it.y)
        fields = [str(it.seq), str(it.current), str(it.frame), str(it.command),
                  _num(it.param1), _num(it.param2), _num(it.param3), _num(it.param4),
                  x, y, _num(it.z), str(it.autocontinue)]
        lines.append("\t".join(fields))
    return "\n".join(lines) + "\n"


def parse_wpl(text: str, source: str = "<text>") -> list[MissionItem]:
    lines = text.splitlines()
    if not lines or lines[0].strip() != HEADER:
        raise MissionFileError(f"{source}: not a QGC WPL 110 file (first line must be "
                               f"{HEADER!r})")
    items: list[MissionItem] = []
    for lineno, raw in enumerate(lines[1:], 2):
        if not raw.strip():
            continue
        f = raw.split()
        if len(f) != 12:
            raise MissionFileError(f"{source}:{lineno}: expected 12 fields, found {len(f)}")
        try:
            seq, current, frame, command = (int(v) for v in f[0:4])
            p1, p2, p3, p4 = (float(v) for v in f[4:8])
            xf, yf, z = float(f[8]), float(f[9]), float(f[10])
            autocontinue = int(float(f[11]))
        except ValueError as exc:
            raise MissionFileError(f"{source}:{lineno}: {exc}") from None
        if seq != len(items):
            raise MissionFileError(f"{source}:{lineno}: sequence {seq} where {len(items)} "
                                   f"was expected; renumber the items from 0")
        scale = 1e7 if frame in GLOBAL_FRAMES else 1.0
        items.append(MissionItem(seq=seq, frame=frame, command=command, current=current,
                                 autocontinue=autocontinue, param1=p1, param2=p2, param3=p3,
                                 param4=p4, x=int(round(xf * scale)), y=int(round(yf * scale)),
                                 z=z))
    return items


def load_wpl(path: str | os.PathLike) -> list[MissionItem]:
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as exc:
        raise MissionFileError(f"cannot read mission file {os.fspath(path)!r}: "
                               f"{exc.strerror or exc}") from None
    return parse_wpl(text, os.fspath(path))


def save_wpl(path: str | os.PathLike, items: list[MissionItem] | tuple[MissionItem, ...]) -> None:
    """Atomic write (temporary file in the same folder, then rename)."""
    write_text_atomic(path, format_wpl(items), encoding="utf-8", error_cls=MissionFileError,
                      what="mission file")


def geo_file(mission_file: str | os.PathLike, mission_type: int) -> str:
    """Where `--mission FILE` keeps the fence (FILE.fence) and rally points (FILE.rally),
    in the same QGC WPL 110 format (MAVProxy's `fence save` / `rally save` write it too)."""
    suffix = {1: ".fence", 2: ".rally"}.get(mission_type)
    if suffix is None:
        raise ValueError(f"mission type {mission_type} has no separate file")
    return os.fspath(mission_file) + suffix
