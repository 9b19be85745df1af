"""User-facing errors of the bridge program (printed in one line by the CLI)."""


class BridgeError(Exception):
    user_facing = True


class PeerLost(BridgeError):
    """The FC died, hung or left during a run."""


class StartupCheckFailed(BridgeError):
    """A start-up check of the paper's procedure (section 4.2) failed."""
