"""``python -m vibkit``: the command line (see :mod:`vibkit.cli`)."""

import sys

from .cli.main import main

sys.exit(main())
