"""Fleet history: measurements of many escalators over years, trends and forecasts of chain elongation.

The public names are those of :mod:`vibkit.fleet.history`.
"""

from .history import *  # noqa: F401,F403
from .history import __all__  # noqa: F401
