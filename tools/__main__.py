import sys

from silbridge.tools.cli import main

sys.exit(main())
