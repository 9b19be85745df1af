"""The `silbridge` command (console script) and `python -m silbridge`.

The platform check comes first, before any subcommand imports the C extensions; then
the command line proper (tools/cli/cli.py) takes over.
"""

from __future__ import annotations

import os
import sys

# One OpenBLAS thread, set before anything imports numpy: our matrices are small (the
# oversampled IMU's per-step block product), and a second BLAS thread spins on the other core
# after each product. At 32 kHz IMU (`fly --processes 1`, 4 alternating pairs) one thread was
# faster in every pair and used ~0.1 s less CPU per run; at 1 kHz no difference. A value the
# user set is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


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
