"""A Dask worker plugin that warms each worker once: the work's imports and compiled kernels loaded when the
worker joins, not by its first task.

:func:`vibkit.runtime.cluster.warm_workers` registers :class:`WarmUp` with a client: every worker of the cluster,
and every worker that joins it later, calls the plugin's function once (a sweep's: its base scene simulated for a
moment; a fleet scan's: the analysis imported).  The function is sent by reference (its module and name), so the
workers need vibkit installed, as they do for the work itself.  A warm-up that fails is logged on the worker and
otherwise ignored: the work then meets the same error and reports it where it belongs.

Only the Dask paths import this module (it imports ``distributed``).
"""

from __future__ import annotations

import logging

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["WarmUp"]

_LOG = logging.getLogger("vibkit.runtime.worker_warmup")


class WarmUp(WorkerPlugin):
    """Call ``fn(*args)`` once in each worker process as it starts (or when registered)."""

    idempotent = False

    def __init__(self, fn, args=()):
        self.fn = fn
        self.args = tuple(args)

    def setup(self, worker):
        try:
            self.fn(*self.args)
        except Exception as exc:  # noqa: BLE001 - a warm-up never fails the worker; the work reports its errors
            _LOG.warning(
                "vibkit warm-up %s failed: %s: %s", getattr(self.fn, "__name__", self.fn), type(exc).__name__, exc
            )
