"""The worn link's signature's simulated runs: the one step of the signature that needs the model's compiled kernels.

:mod:`vibkit.diagnose.link_signature` keeps every run's map on disk; it imports this module only where a kept run
misses, so that ``vibkit links`` on an escalator it has seen before loads neither the model's kernels nor numba.
"""

from __future__ import annotations

from ..analyses.simulation import simulate

__all__ = ["simulate_run"]


def simulate_run(scene, duration, variable):
    """Simulate ``scene`` for ``duration`` [s]: its time [s], its output ``variable`` and the sprocket's angle [rad]."""
    ds = simulate(scene, duration=duration, progress=False)
    return ds.time.values, ds[variable].values, ds.sprocket_angle.values
