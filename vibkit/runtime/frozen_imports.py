"""A command-line process imports its command's libraries with the garbage collector paused, then freezes them.

Importing numpy, scipy, pandas, xarray and matplotlib makes about a million objects that live as long as the
process.  While they are being made, Python's collector runs now and then over everything made so far (three full
collections and about 470 younger ones for the report's imports), and after them every full collection of the
command's own work walks them again.  None of it frees anything: a module's objects are not garbage.  Measured
2026-12-08 on the project's 2-core machine (Python 3.11.7): the Las Palmas report spent 0.20-0.23 CPU-s collecting
during its imports and 0.13 during its work, 0.05-0.07 with the imports frozen.

:func:`import_frozen` imports the named modules with the collector off and moves what they made into the
permanent generation (:func:`gc.freeze`), where no collection looks.  Only a command's ``run`` calls it (the
report's), with the modules it imports anyway (its module's ``LIBRARY``), once its arguments are checked, and only
where :func:`vibkit.cli.main` runs the process's own command line (``args.own_process``): a library user's
process keeps its collector as it set it.  Garbage the imports leave
in cycles (a few objects) is frozen with them and freed at the process's exit.
"""

from __future__ import annotations

import gc
import importlib

__all__ = ["import_frozen"]


def import_frozen(names) -> None:
    """Import the modules ``names`` (dotted names) with the garbage collector paused, then freeze every object the
    process holds; the collector is left as it was (on, unless the caller had switched it off)."""
    was_on = gc.isenabled()
    gc.disable()
    try:
        for name in names:
            importlib.import_module(name)
    finally:
        gc.freeze()
        if was_on:
            gc.enable()
