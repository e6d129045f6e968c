"""``python -m skatetrace.cli ...``: the command line, as the ``skatetrace`` script runs it."""

import sys

from .commands import main

sys.exit(main())
