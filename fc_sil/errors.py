"""Errors of the flight-controller package that a user can act on.

Each class sets ``user_facing = True``: the `silbridge` command prints the
message on one line (exit status 2). Messages say what to do next.
"""

from __future__ import annotations


class FcError(Exception):
    """Base of the user-facing flight-controller errors."""

    user_facing = True


class ParamError(FcError, ValueError):
    """A parameter name or value was refused; the old value is kept."""


class InputError(FcError, ValueError):
    """A target or sensor input was refused (NaN, inf, out of range)."""


class CoreBuildError(FcError, ImportError):
    """The compiled core is missing."""
