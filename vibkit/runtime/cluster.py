"""Where parallel work runs: a Dask ``distributed`` client, a local cluster by default.

Sweeps (:mod:`vibkit.sweep.run`) and fleet scans (:mod:`vibkit.fleet.history`) both submit their runs through
:func:`dask_client`, so a user who already runs a Dask cluster points vibkit at it with one address
(``--scheduler tcp://host:8786``, or Dask's own configuration ``scheduler-address`` /
``DASK_SCHEDULER_ADDRESS``), and everyone else gets one worker process per core.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os

__all__ = ["dask_client", "dask_pays", "default_workers", "scheduler_address", "warm_workers", "LOCAL_CLUSTER_START_S"]

#: seconds before a fresh local cluster computes anything: the cluster started and each worker warm (vibkit
#: imported, the kernels loaded from their cache, :func:`warm_workers`), the workers warming at once on their own
#: cores. Measured on the project's 2-core machine: a sweep on a fresh cluster of one worker costs 6 CPU-s more than
#: the same runs in the process (benchmarks/results/user_costs.md, rows "sweep")
LOCAL_CLUSTER_START_S = 6.0


def default_workers() -> int:
    """Worker processes of a local cluster: one per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def dask_pays(seconds_left: float, workers: int) -> bool:
    """Whether work that would take ``seconds_left`` more in this process ends sooner on a fresh local cluster of
    ``workers`` processes: ``seconds_left * (1 - 1 / workers) > LOCAL_CLUSTER_START_S`` (the work shared evenly,
    after the cluster's start-up).  One worker never pays: it does the same work after the start-up."""
    w = max(1, int(workers))
    return float(seconds_left) * (1.0 - 1.0 / w) > LOCAL_CLUSTER_START_S


def scheduler_address(scheduler: str | None = None) -> str | None:
    """The running Dask scheduler work goes to: ``scheduler``, else Dask's configuration (``scheduler-address``,
    ``DASK_SCHEDULER_ADDRESS``) where Dask is installed; None: none (a local cluster would be started)."""
    if scheduler:
        return scheduler
    try:
        import dask.config
    except ImportError:
        return None
    return dask.config.get("scheduler-address", None) or None


def warm_workers(client, fn, *args) -> None:
    """Have every worker of ``client``'s cluster call ``fn(*args)`` once, now and as it joins later (a worker
    plugin, :class:`vibkit.runtime.worker_warmup.WarmUp`): a sweep's or a scan's imports and compiled kernels
    loaded once per worker, not by each worker's first task.  Returns when the workers present have warmed up
    (together, each on its own core).  ``fn`` must be a module-level function (sent by its name)."""
    from .worker_warmup import WarmUp  # imports distributed: only where Dask runs

    key = f"{fn.__module__}.{fn.__qualname__}{args!r}".encode()
    client.register_plugin(WarmUp(fn, args), name=f"vibkit-warm-{hashlib.sha1(key).hexdigest()[:16]}")


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, *, n_workers: int | None = None):
    """A ``distributed.Client``, closed (and its local cluster shut down) on exit.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``). Without it, Dask's configuration
        (``scheduler-address``, also read from ``DASK_SCHEDULER_ADDRESS``) is used; failing that, a
        local cluster of worker *processes* (one thread each: the compiled kernels hold the GIL).
    n_workers : int, optional
        Processes of the local cluster (default: one per core). Ignored with a scheduler address.
    """
    from .extras import require

    distributed = require("distributed", "parallel", "sweeps and fleet scans on worker processes (Dask)")
    import dask

    Client, LocalCluster = distributed.Client, distributed.LocalCluster
    address = scheduler or dask.config.get("scheduler-address", None)
    if address:
        with Client(address) as client:
            yield client
        return
    if n_workers is not None and int(n_workers) < 1:
        raise ValueError(f"n_workers must be >= 1, got {n_workers!r}")
    n = int(n_workers) if n_workers else default_workers()
    # dashboard on a free port: the default 8787 is often taken (another cluster, another user)
    # no dashboard: the scheduler's HTTP server would otherwise bind port 8787 (or warn and leak a
    # socket when another process holds it)
    with (
        LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
            silence_logs=logging.ERROR,
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client
