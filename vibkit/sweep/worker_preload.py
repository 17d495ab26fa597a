"""vibkit's Dask worker preload: a worker that starts with it imports vibkit's analyses and loads the compiled
kernels of the shipped forward scene before it takes any task.

    dask worker tcp://scheduler-host:8786 --nworkers 1 --nthreads 1 --preload vibkit.sweep.worker_preload

A sweep (:func:`vibkit.sweep`) and a fleet scan (:meth:`vibkit.fleet.FleetDB.scan`) warm every worker of the
cluster they are given anyway (:func:`vibkit.runtime.cluster.warm_workers`, a sweep with its own base scene); the
preload moves that cost to the worker's start, before the first sweep or scan waits for it
(docs/guide/cluster.md).
"""

from __future__ import annotations

from ..fleet import scan as _scan
from ..model.scene import load_scene
from . import run as _run

__all__ = ["dask_setup", "PRELOAD_SCENE"]

#: the shipped scene whose kernels a preloaded worker loads
PRELOAD_SCENE = "thesis-forward"


def dask_setup(worker=None):
    """Dask's preload hook: the fleet analysis imported, the shipped forward scene simulated for a moment."""
    _scan._warm()
    scene = load_scene(PRELOAD_SCENE)
    _run._warm(scene.text, scene.source)
