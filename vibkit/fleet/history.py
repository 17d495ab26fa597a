"""Compatibility: the fleet history was split into modules named after what they hold.

This name keeps ``from vibkit.fleet.history import ...`` working for the public names; new code imports
from :mod:`vibkit.fleet` (or from the module that holds a name: :mod:`~vibkit.fleet.errors`,
:mod:`~vibkit.fleet.dates`, :mod:`~vibkit.fleet.trends`, :mod:`~vibkit.fleet.measurement`,
:mod:`~vibkit.fleet.catalogue`, :mod:`~vibkit.fleet.scan`, :mod:`~vibkit.fleet.storage`).
"""

from . import *  # noqa: F401,F403
from . import __all__  # noqa: F401
from .catalogue import CATALOGUE_OPTIONAL  # noqa: F401
from .scan import RECORDING_SUFFIXES  # noqa: F401
from .storage import APPLICATION_ID, SCHEMA_VERSION  # noqa: F401
from .trends import SECONDS_PER_YEAR, rank_units, unit_trend  # noqa: F401
