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


# (column name, lowest, highest) of the integer columns: the MISSION_ITEM_INT field widths,
# so an item read from a file always fits the message that carries it to a ground station.
_INT_COLUMNS = (("seq", 0, 65535), ("current", 0, 255), ("frame", 0, 255),
                ("command", 0, 65535))
_INT32 = (-2**31, 2**31 - 1)


def parse_wpl(text: str, source: str = "<text>") -> list[MissionItem]:
    """Items in file order; raise MissionFileError naming source and line on a bad line."""
    lines = text.splitlines()
    if not lines or lines[0].strip() != HEADER:
        raise MissionFileError(f"{source}:1: not a QGC WPL 110 file (first line must be "
                               f"{HEADER!r})")
    items: list[MissionItem] = []
    for lineno, raw in enumerate(lines[1:], 2):
        if not raw.strip():
            continue
        f = raw.split()
        if len(f) != 12:
            raise MissionFileError(f"{source}:{lineno}: expected 12 fields, found {len(f)}")
        try:
            ints = [int(v) for v in f[0:4]]
            p1, p2, p3, p4 = (float(v) for v in f[4:8])
            xf, yf, z = float(f[8]), float(f[9]), float(f[10])
            autocontinue = float(f[11])
        except ValueError as exc:
            raise MissionFileError(f"{source}:{lineno}: {exc}") from None
        for (what, lo, hi), v in zip(_INT_COLUMNS, ints):
            if not lo <= v <= hi:
                raise MissionFileError(f"{source}:{lineno}: {what} {v} is outside {lo}..{hi}")
        seq, current, frame, command = ints
        if autocontinue not in (0.0, 1.0):
            raise MissionFileError(f"{source}:{lineno}: autocontinue must be 0 or 1, "
                                   f"got {f[11]!r}")
        if seq != len(items):
            raise MissionFileError(f"{source}:{lineno}: sequence {seq} where {len(items)} "
                                   f"was expected; renumber the items from 0")
        scale = 1e7 if frame in GLOBAL_FRAMES else 1.0
        xy = []
        for what, v in (("x/latitude", xf), ("y/longitude", yf)):
            scaled = v * scale
            # x and y travel as int32 (degrees*1e7 in global frames)
            if not (math.isfinite(scaled) and _INT32[0] <= round(scaled) <= _INT32[1]):
                raise MissionFileError(f"{source}:{lineno}: {what} {v!r} is out of range")
            xy.append(int(round(scaled)))
        items.append(MissionItem(seq=seq, frame=frame, command=command, current=current,
                                 autocontinue=int(autocontinue), param1=p1, param2=p2,
                                 param3=p3, param4=p4, x=xy[0], y=xy[1], z=z))
    return items


def load_wpl(path: str | os.PathLike) -> list[MissionItem]:
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise MissionFileError(f"cannot read mission file {os.fspath(path)!r}: "
                               f"{exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise MissionFileError(f"{os.fspath(path)}:{line}: byte 0x{data[exc.start]:02x} is not "
                               f"UTF-8 text; save the file as UTF-8") from None
    return parse_wpl(text, os.fspath(path))


def item_line(path: str | os.PathLike, index: int) -> int:
    """The line of `path` that holds item `index` (for errors found after loading: a store
    refusing the list names the item, and the user wants the line)."""
    with open(path, "rb") as f:
        lines = f.read().decode("utf-8").splitlines()
    n = -1
    for lineno, raw in enumerate(lines[1:], 2):
        if raw.strip():
            n += 1
            if n == index:
                return lineno
    return len(lines) + 1      # past the last item: a list that ends too soon


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
