"""`python -m silbridge.tools`: the `silbridge` command without its console script."""

import sys

from silbridge.tools.cli.cli import main

sys.exit(main())
