"""User-facing errors of the MAVLink HIL transport (printed in one line by the CLI)."""

from __future__ import annotations

from silbridge.mavlink.errors import MavlinkUserError


class HilError(MavlinkUserError):
    """Base of the HIL transport's errors."""


class HilInputError(HilError):
    """The simulator's HIL stream is unusable: NaN, time going backwards, or a stall.

    The FC end commands its safe state (motors to MOT_PWM_MIN, disarmed) before raising."""


class HilPeerLost(HilError):
    """The other end disconnected or went silent."""


class HilConfigError(HilError):
    """A run the HIL messages cannot carry exactly (e.g. sample times off the microsecond)."""


class HilConnectError(HilError):
    """Could not listen on or connect to the HIL address."""
