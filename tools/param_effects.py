"""Where each parameter acts in the simulator, found in the code itself; and the GCS list.

docs/params.md shows, per parameter, "acts" with where, or "no effect in SIL". Rather than a
second hand-kept table that could drift from the code, the answer is read from the sources:

* a C-core parameter (FC_PARAM) acts in the C core (its struct field is read by the loops);
* a host parameter acts in the Python modules that name it in a string literal: "NAME", or
  a name template such as f"RC{c}_MIN" / f"FLTMODE{i}" that covers a numbered family;
* a host parameter no module names is accepted, stored, served over MAVLink and saved in
  .parm files, and has no effect in SIL (serial ports, LEDs, sensor ids, ...).

``gcs_params()`` reads docs/gcs_params.txt: the parameters QGroundControl and MAVProxy read
from an ArduCopter, each with ArduCopter 4.6.0's type and the files that read it.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GCS_LIST = ROOT / "docs" / "gcs_params.txt"
NO_EFFECT = "no effect in SIL"
# Modules whose code acts on parameters (the parameter machinery itself names none).
_SCAN = ("fc_sil/*.py", "mavlink/*.py")
_SKIP = {"params.py", "param_store.py", "params_file.py", "param_protocol.py", "param_types.py"}


@functools.lru_cache(maxsize=1)
def _sources() -> tuple[tuple[str, str], ...]:
    out = []
    for pattern in _SCAN:
        for path in sorted(ROOT.glob(pattern)):
            if path.name not in _SKIP:
                out.append((f"{path.parent.name}/{path.name}", path.read_text()))
    return tuple(out)


def _pattern(name: str) -> re.Pattern:
    """The name quoted, each number in it also matching a {placeholder} of a template."""
    parts = re.split(r"(\d+)", name)
    body = "".join(f"(?:{p}|\\{{[^}}\"']*\\}})" if p.isdigit() else re.escape(p)
                   for p in parts)
    return re.compile(f"[\"']{body}[\"']")


def where_acts(p) -> list[str]:
    """Files whose code reads parameter ``p`` (a ParamDef); ["C core"] for core ones."""
    if not p.host:
        return ["C core"]
    pat = _pattern(p.name)
    return [f for f, text in _sources() if pat.search(text)]


def effect(p) -> str:
    files = where_acts(p)
    return "acts: " + ", ".join(files) if files else NO_EFFECT


def gcs_params(path: Path = GCS_LIST) -> dict[str, list[str]]:
    """name -> sources, from docs/gcs_params.txt (comment lines start with #)."""
    return {name: sources for name, (_, sources) in gcs_param_types(path).items()}


def gcs_param_types(path: Path = GCS_LIST) -> dict[str, tuple[str, list[str]]]:
    """name -> (ArduCopter type: INT8/INT16/INT32/FLOAT, sources)."""
    out: dict[str, tuple[str, list[str]]] = {}
    for line in path.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            name, typ, *sources = line.split()
            out[name] = (typ, sources)
    return out
