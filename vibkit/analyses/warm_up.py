"""The compiled kernels that vibkit's commands run, compiled ahead: ``vibkit warm``.

A command compiles the numba kernels it runs the first time it runs them on a machine, after an install or an
upgrade, and keeps them in numba's cache (:mod:`vibkit.runtime.kernel_cache`): that first command waits about a
minute.  :func:`warm_up` runs each of the model's analyses and closures, and each of the signal layer's compiled
filters, once on a short input, so that a site that would rather wait at install (an image build, a deployment
step) does, and every command after it starts warm.  Run again with the kernels cached, it loads them (seconds).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

import numpy as np

from ..model.scene import load_scene
from ..runtime.kernel_cache import cache_dir
from ..signal.hampel import hampel
from ..signal.orders import vold_kalman
from ..signal.ride import half_cycle_peaks
from .integrate import _cold
from .simulation import simulate

__all__ = ["WarmStep", "warm_up", "STEPS"]

#: simulated time of each model step [s]: every kernel of a run is compiled by its first steps
SIMULATED_S = 0.2


@dataclasses.dataclass(frozen=True)
class WarmStep:
    """One step of :func:`warm_up`: what it compiled (or loaded), and its CPU time [s]."""

    what: str
    cpu_s: float


def _simulate(name: str, **chain) -> Callable[[], None]:
    def run():
        scene = load_scene(name)
        if chain:
            worn = ((1, scene.chain.link_pitch + 1e-3),)
            scene = dataclasses.replace(scene, chain=dataclasses.replace(scene.chain, worn_links=worn))
            scene = scene.with_solver(closure=chain["closure"])
        simulate(scene, duration=SIMULATED_S, progress=False)

    return run


def _signal_kernels():
    fs = 100.0
    t = np.arange(4000) / fs
    x = np.sin(2 * np.pi * 3.75 * t)
    gapped = x.copy()
    gapped[100] = np.nan  # a gapped record takes the compiled Hampel filter (a short gapless one takes numpy's)
    hampel(gapped, half_window=5)
    vold_kalman(x, fs, 2 * np.pi * 3.75 * t, bandwidth_hz=0.5)
    half_cycle_peaks(x)


#: (what, how): the analyses, closures and filters the commands run
STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("kinematics (the study's kinematic scene)", _simulate("thesis-kinematics")),
    ("inverse dynamics (leon)", _simulate("leon")),
    ("forward dynamics, the closure tabulated over one pitch (the study's forward scene)", _simulate("thesis-forward")),
    ("forward dynamics with passengers and the speed controller (las-palmas)", _simulate("las-palmas")),
    ("a worn chain closed run by run (the worn-link signature's runs)", _simulate("thesis-forward", closure="runs")),
    ("a worn chain closed exactly at every evaluation", _simulate("thesis-forward", closure="exact")),
    ("the signal layer's compiled filters (Hampel, Vold-Kalman, half-cycle peaks)", _signal_kernels),
)


def warm_up(on_step: Callable[[int, str], None] | None = None) -> tuple[bool, list[WarmStep], str | None]:
    """Compile (or load from numba's cache) every kernel vibkit's commands run.

    Parameters
    ----------
    on_step : callable, optional
        Called as ``on_step(i, what)`` before step ``i`` (0-based) of :data:`STEPS`: a progress report.

    Returns
    -------
    cold : bool
        Whether the model's kernels were not cached before (they were compiled now).
    steps : list of WarmStep
        Each step and its CPU time [s].
    folder : str or None
        numba's cache folder (None: next to vibkit's modules, in their ``__pycache__``).
    """
    cold = _cold("dopri5")
    steps = []
    for i, (what, run) in enumerate(STEPS):
        if on_step is not None:
            on_step(i, what)
        c0 = time.process_time()
        run()
        steps.append(WarmStep(what, time.process_time() - c0))
    return cold, steps, cache_dir()
