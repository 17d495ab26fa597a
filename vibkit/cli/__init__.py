"""The ``vibkit`` command line: a thin layer over the library.

``vibkit.cli.main(argv)`` runs one command and returns its exit status.
"""

from .app import main

__all__ = ["main"]
