"""Optional dependencies, installed as extras of the package, and the one-line error when one is missing.

The base install reads recordings, simulates, analyses and writes reports; what only some work needs
is an extra (``pip install 'vibkit[EXTRA]'``):

==========  =================================  ===================================================
extra       installs                           for
==========  =================================  ===================================================
seismic     obspy                              miniSEED, SAC, GSE2 and the other formats obspy reads
parallel    distributed (Dask), zarr           sweeps, and fleet scans on several worker processes
tdms        npTDMS                             NI TDMS files
postgres    psycopg                            a fleet history on a PostgreSQL server
==========  =================================  ===================================================

:func:`require` imports a module of an extra or raises :class:`MissingExtraError`, a ``ValueError``
whose message names the work, the package and the extra (the command line prints it in one line,
exit status 1).
"""

from __future__ import annotations

import importlib

__all__ = ["MissingExtraError", "require", "EXTRAS"]

#: extra -> the packages it installs (as pyproject.toml declares them)
EXTRAS = {
    "seismic": ("obspy",),
    "parallel": ("distributed", "zarr"),
    "tdms": ("npTDMS",),
    "postgres": ("psycopg",),
}


class MissingExtraError(ValueError):
    """An optional dependency is not installed: the message names what needs it and the extra that installs it."""


def require(module: str, extra: str, what: str):
    """Import ``module`` (a package of extra ``extra``), or raise :class:`MissingExtraError`.

    Parameters
    ----------
    module : str
        The module to import (``"obspy"``, ``"distributed"``, ``"zarr"``).
    extra : str
        The extra of :data:`EXTRAS` that installs it.
    what : str
        What needs it, for the message (``"sweeps"``).
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        package = module.split(".")[0]
        raise MissingExtraError(
            f"{what} needs {package}, which is not installed: pip install 'vibkit[{extra}]'"
        ) from None
