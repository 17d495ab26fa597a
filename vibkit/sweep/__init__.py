"""Parameter sweeps: one scene, some keys varied, runs on Dask, results streamed to Zarr.

``vibkit.sweep`` (the attribute of the package ``vibkit``) is the function :func:`vibkit.sweep.run.sweep`;
the modules are :mod:`vibkit.sweep.run` and its neighbours. Imports only the standard library at load.
"""

from .run import *  # noqa: F401,F403
from .run import __all__  # noqa: F401
