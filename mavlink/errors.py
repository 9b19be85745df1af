"""User-facing errors of the MAVLink layer.

Each message says what to do next; the `silbridge` command prints it in one line (exit 2).
"""

from __future__ import annotations


class MavlinkUserError(Exception):
    user_facing = True


class EndpointError(MavlinkUserError):
    """A --gcs URL that cannot be parsed or opened."""


class ParamFileError(MavlinkUserError):
    """A .parm file that cannot be read or written."""


class MissionFileError(MavlinkUserError):
    """A QGC WPL mission file that cannot be read or written."""
