"""Our FC's parameters for every flight of a campaign (`bench`, `ablate`, `tune`).

`--params FILE` (an ArduPilot .parm file, read-only: a campaign never writes it) first,
then each `--param NAME=VALUE` over it, checked once, up front, as the FC applies them:
a missing or unreadable file, or a refused --param, stops the command before any
flight. A file's entry the FC refuses (a name it does not have, a value out of range)
is left out and said, as `silbridge fly --params` does, so one file flies alike in both.
"""

from __future__ import annotations

import os
import sys

from silbridge.tools.cli.flight_args import parse_params


class RunParamsError(ValueError):
    user_facing = True


def run_params(param_file: str | None, items: list[str], say=None) -> dict[str, float]:
    """name -> value: the file's accepted entries, then the --param overrides.
    say(line): where the file's refused entries are reported (default: stderr)."""
    from silbridge.fc_sil.errors import ParamError
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.mavlink.errors import ParamFileError
    from silbridge.mavlink.gcs.params_file import load_parm

    say = say or (lambda line: print(line, file=sys.stderr))
    core = FlightCore()
    params: dict[str, float] = {}
    if param_file:
        if not os.path.isfile(param_file):
            what = "is a folder" if os.path.isdir(param_file) else "no such file"
            raise RunParamsError(f"--params {param_file}: {what}; give an existing .parm file "
                                 f"(it is read, never written)")
        try:
            entries = load_parm(param_file)
        except ParamFileError as exc:
            raise RunParamsError(str(exc)) from None
        for name, value in entries:
            try:
                core.set_param(name, value)
            except ParamError as exc:
                say(f"--params {param_file}: {exc} (entry ignored)")
                continue
            params[name.upper()] = value
    for name, value in parse_params(items).items():
        try:
            core.set_param(name, value)
        except ParamError as exc:
            raise RunParamsError(f"--param {exc}") from None
        params[name] = value
    return params
