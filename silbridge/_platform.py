"""Linux only, said once at the start of the command line.

The rings live in POSIX shared memory under /dev/shm, the FC's loop sleeps and spins
on Linux's monotonic clock, and the C extensions link librt: on any other system the
first run would fail somewhere deep with a confusing error, so the command refuses
at once with one line instead.
"""

from __future__ import annotations

import sys


class UnsupportedPlatformError(RuntimeError):
    """silbridge runs on Linux only."""

    user_facing = True


def require_linux(platform: str | None = None) -> None:
    """Raise UnsupportedPlatformError unless this is Linux (`platform`: sys.platform)."""
    platform = sys.platform if platform is None else platform
    if not platform.startswith("linux"):
        raise UnsupportedPlatformError(
            f"silbridge runs on Linux only (this is {platform}): use a Linux machine, "
            "a Linux VM, or WSL 2 on Windows")
