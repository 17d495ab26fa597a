"""Parameter sweeps: one scene, some keys varied, runs on Dask, results streamed to Zarr.

``vibkit.sweep`` (the attribute of the package ``vibkit``) is the function :func:`vibkit.sweep.run.sweep`.
The modules: :mod:`vibkit.sweep.plan` (``--vary``, axes, the plan, varied scene texts),
:mod:`vibkit.sweep.records` (status codes, summary names), :mod:`vibkit.sweep.store` (the Zarr store,
the assembled result) and :mod:`vibkit.sweep.run` (the runs on Dask, :func:`sweep`). Imports only the
standard library at load.
"""

from .plan import SweepError, SweepPlan, parse_vary, plan_sweep, to_toml, varied_text  # noqa: F401
from .records import STATUS, SUMMARIES  # noqa: F401
from .run import summarize, sweep  # noqa: F401
from .store import open_sweep  # noqa: F401

__all__ = [
    "sweep",
    "parse_vary",
    "plan_sweep",
    "SweepPlan",
    "SweepError",
    "summarize",
    "SUMMARIES",
    "STATUS",
    "open_sweep",
]
