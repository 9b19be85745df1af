"""Exceptions of the bridge that the `silbridge` command shows to the user.

Each sets ``user_facing = True``: the CLI prints the message in one line and
exits with status 2, so each message names the offending thing and says what
to do next. Scenario and simulator errors come before a run starts;
`BridgeError` and its kinds during one (the FC lost, a start-up check failed).
"""


class ScenarioError(ValueError):
    """A scenario file (or override) is invalid: unknown key, bad value, missing field."""

    user_facing = True


class SimulatorError(RuntimeError):
    """The simulator cannot start (model missing, bad initial conditions, bad rate)."""

    user_facing = True


class BridgeError(Exception):
    """A run of the bridge program failed (bridge/bridge_driver.py)."""

    user_facing = True


class PeerLost(BridgeError):
    """The FC died, hung or left during a run."""


class LockstepBroken(BridgeError):
    """The FC answered a step it had promised to answer with nothing (FC_SYNC_NS)."""


class StartupCheckFailed(BridgeError):
    """A start-up check of the paper's procedure (section 4.2) failed."""
