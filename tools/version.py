"""The installed distribution's version: the one lookup `silbridge --version`, the logs'
metadata and `silbridge.__version__` all read. Standard library only, so importing it
costs nothing (the CLI's `--version` must not load JSBSim)."""

from __future__ import annotations


def package_version() -> str:
    """The version in pyproject.toml as installed; "unknown" outside an install."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("silbridge")
    except PackageNotFoundError:
        return "unknown"
