"""Helpers shared by the tests and the benchmark scripts: what several of them built each for itself.

* :mod:`support.chain`: synthetic chain signals (a harmonic family of the link-pass frequency, a family
  on a given phase, a family under a wandering speed, the fleet's recordings);
* :mod:`support.drift`: sources whose frequency drifts (a linear drift, a random wander, a gait-like cadence);
* :mod:`support.phone`: a link-pass line added to a phone's channels at a level over each channel's own floor;
* :mod:`support.recording`: the recording dataset the readers return, built from arrays;
* :mod:`support.cli`: the ``run`` fixture (``vibkit.cli.main`` in-process) and the one-line error check
  of a command;
* :mod:`support.contracts`: the one-line ``RecordingError`` check of a reader.

The tests import it as ``support`` (``pythonpath`` in pyproject.toml's pytest section puts ``tests/`` on
the path); the benchmark scripts get it from ``benchmarks/_common.py``. :mod:`support.cli` and
:mod:`support.contracts` need pytest, the others only numpy, scipy and xarray.
"""

from . import chain, drift, phone, recording

__all__ = ["chain", "drift", "phone", "recording"]
