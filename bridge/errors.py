"""Exceptions of the bridge that the `silbridge` command shows to the user.

Both set ``user_facing = True``: the CLI prints the message in one line and
exits with status 2, so each message names the offending thing and says what
to do next.
"""


class ScenarioError(ValueError):
    """A scenario file (or override) is invalid: unknown key, bad value, missing field."""

    user_facing = True


class SimulatorError(RuntimeError):
    """The simulator cannot start (model missing, bad initial conditions, bad rate)."""

    user_facing = True
