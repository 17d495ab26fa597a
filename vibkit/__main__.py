"""``python -m vibkit``: the command line (see :mod:`vibkit.cli`)."""

import sys

from .cli import main

sys.exit(main())
