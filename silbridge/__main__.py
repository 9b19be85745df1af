"""The `silbridge` command (console script) and `python -m silbridge`.

The platform check comes first, before any subcommand imports the C extensions; then
the command line proper (tools/cli/cli.py) takes over.
"""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    from silbridge._platform import UnsupportedPlatformError, require_linux

    try:
        require_linux()
    except UnsupportedPlatformError as exc:
        print(f"silbridge: error: {exc}", file=sys.stderr)
        return 2
    from silbridge.tools.cli.cli import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
