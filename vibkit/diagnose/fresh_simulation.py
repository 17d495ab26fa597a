"""A scene simulated afresh: the one module on the report's and the comparison's paths that imports the model.

:mod:`vibkit.diagnose.kept_simulation` imports it only where no kept run serves, and
:mod:`vibkit.diagnose.comparison` only where it is given a scene rather than a result, so that a warm
``vibkit report`` loads neither the model's kernels nor numba.
"""

from __future__ import annotations

from ..analyses.simulation import simulate

__all__ = ["simulate_fresh"]


def simulate_fresh(scene, *, duration=None, progress=False):
    """:func:`vibkit.simulate` of ``scene`` for ``duration`` [s] (None: the scene's own)."""
    return simulate(scene, duration=duration, progress=progress)
