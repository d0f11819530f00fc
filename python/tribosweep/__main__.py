"""``python -m tribosweep``: the command line (see :mod:`tribosweep.cli`)."""

import sys

from .cli import main

sys.exit(main())
