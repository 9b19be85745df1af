"""Optional dependencies: imported only where used, refused with the extra that brings them.

`pip install .` installs the light set (pyproject.toml: what `fly`, `bench` with its
report and the GCS server import). Tuning, Ray and the ground-station clients are
extras; code that needs one checks for it here first, so a light install meets one
line naming the extra instead of an ImportError from deep inside a run. silbridge is
installed from its source folder (it is not on PyPI), hence the hint's form.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterable


class MissingExtraError(ImportError):
    """An optional dependency is not installed; the message names the extra."""

    user_facing = True


def install_hint(extra: str) -> str:
    """How to add an extra to this installation."""
    return f"in the silbridge source folder run: pip install '.[{extra}]'"


def require(modules: Iterable[str], extra: str, feature: str) -> None:
    """MissingExtraError unless every module (import name) can be imported."""
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise MissingExtraError(f"{feature} needs {', '.join(missing)}, from the '{extra}' "
                                f"extra: {install_hint(extra)}")
