"""Write tuned gains as an ArduPilot .parm file (`silbridge fly --params FILE`,
MAVProxy `param load`, Mission Planner), validated first against the FC's own
declaration so the file never holds a value the FC would refuse."""

from __future__ import annotations

from pathlib import Path

from silbridge.fc_sil import params as P
from silbridge.fc_sil.flight_core import FlightCore
from silbridge.mavlink.gcs.params_file import format_parm


def write_parm(path: Path, values: dict, *, header: str = "") -> Path:
    core = FlightCore()
    entries = []
    for name in sorted(values, key=lambda n: P.BY_NAME[n].index):
        stored = core.set_param(name, values[name])    # ParamError on a refused value
        d = P.BY_NAME[name]
        entries.append((name, stored, P.MAV_PARAM_TYPE[d.type]))
    text = (f"# {header}\n" if header else "") + format_parm(entries)
    path = Path(path)
    path.write_text(text)
    return path
