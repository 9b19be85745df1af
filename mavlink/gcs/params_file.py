"""ArduPilot `.parm` files: read, write atomically, apply to a ParamStore.

Format (as MAVProxy's `param save` writes it and Mission Planner reads it): one parameter per
line, NAME then VALUE separated by spaces, a tab or a comma; `#` starts a comment. Integers are
written as integers; floats with the fewest digits that still give back the same float32 (the
width a parameter has on the wire), so a saved file reads back bit for bit.

Writes go to a temporary file in the same folder, are fsynced, then renamed over the target:
a crash mid-save leaves the old file, never a half-written one.
"""

from __future__ import annotations

import math
import os
import struct
from typing import Iterable

from silbridge.mavlink.atomic_file import write_text_atomic
from silbridge.mavlink.errors import ParamFileError
from silbridge.mavlink.gcs.param_types import INT_TYPES, coerce
from silbridge.mavlink.gcs.vehicle_api import ParamStore



def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def format_value(value: float, param_type: int) -> str:
    if param_type in INT_TYPES:
        return str(int(value))
    v = float(value)
    if not math.isfinite(v):
        return repr(v)
    target = _f32(v)
    for digits in range(6, 10):
        text = format(v, f".{digits}g")
        if _f32(float(text)) == target:
            return text
    return repr(v)


def parse_parm(text: str, source: str = "<text>") -> list[tuple[str, float]]:
    """Parse .parm text into (name, value) in file order; raise ParamFileError on bad lines."""
    out: list[tuple[str, float]] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.replace(",", " ").replace("\t", " ").split()
        if len(parts) != 2:
            raise ParamFileError(f"{source}:{lineno}: expected 'NAME VALUE', got {raw.strip()!r}; "
                                 f"fix or delete that line")
        name, value_text = parts
        if len(name) > 16:
            raise ParamFileError(f"{source}:{lineno}: parameter name {name!r} is longer than "
                                 f"16 characters")
        try:
            value = float(value_text)
        except ValueError:
            raise ParamFileError(f"{source}:{lineno}: value {value_text!r} of {name} is not a "
                                 f"number") from None
        out.append((name, value))
    return out


def load_parm(path: str | os.PathLike) -> list[tuple[str, float]]:
    try:
        with open(path, encoding="ascii", errors="replace") as f:
            text = f.read()
    except OSError as exc:
        raise ParamFileError(f"cannot read parameter file {os.fspath(path)!r}: "
                             f"{exc.strerror or exc}") from None
    return parse_parm(text, os.fspath(path))


def format_parm(entries: Iterable[tuple[str, float, int]]) -> str:
    return "".join(f"{name:<16} {format_value(value, ptype)}\n" for name, value, ptype in entries)


def save_parm(path: str | os.PathLike, entries: Iterable[tuple[str, float, int]]) -> None:
    """Atomically write (name, value, MAV_PARAM_TYPE) entries to path."""
    write_text_atomic(path, format_parm(entries), encoding="ascii", error_cls=ParamFileError,
                      what="parameter file")


def store_entries(store: ParamStore) -> list[tuple[str, float, int]]:
    out = []
    for name in store.names():
        value, ptype = store.get(name)
        out.append((name, value, ptype))
    return out


def save_store(path: str | os.PathLike, store: ParamStore) -> None:
    save_parm(path, store_entries(store))


def apply_parm(store: ParamStore, entries: Iterable[tuple[str, float]]) -> list[str]:
    """Set each entry through the store's validation; return one message per refused entry."""
    known = set(store.names())
    problems: list[str] = []
    for name, value in entries:
        if name not in known:
            problems.append(f"{name}: unknown parameter (ignored)")
            continue
        _, ptype = store.get(name)
        v, err = coerce(value, ptype)
        if err is None:
            try:
                err = store.set(name, v)
            except (ValueError, TypeError) as exc:
                err = str(exc)
        if err:
            problems.append(f"{name}: {err} (kept {format_value(store.get(name)[0], ptype)})")
    return problems


def load_into_store(path: str | os.PathLike, store: ParamStore) -> list[str]:
    """`--params FILE` at start: apply FILE if it exists (a missing file is created by the
    first save); return one message per entry the store refused."""
    if not os.path.exists(path):
        return []
    return apply_parm(store, load_parm(path))
