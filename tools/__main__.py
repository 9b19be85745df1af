import sys

from silbridge.tools.cli.cli import main

sys.exit(main())
