"""``python -m skatetrace ...``: the command line, as the ``skatetrace`` script runs it."""

import sys

from .cli import main

sys.exit(main())
