"""``python -m skatetrace ...``: the command line, as the ``skatetrace`` script runs it."""

import sys

from .cli import script

if __name__ == "__main__":  # importing it (as the API reference's generator does) runs nothing
    sys.exit(script())
