"""Kinematic analysis: sweep the chain's advance and solve the position problem at every step."""

from __future__ import annotations

import numpy as np

from ..runtime.progress import Progress
from .results import make_dataset

__all__ = ["kinematic_sweep"]


#: a compiled sweep longer than this many configurations runs in pieces so that progress can be shown
PROGRESS_CHUNK = 1_000_000


def kinematic_sweep(model, start: float, stop: float, step: float, *, rollers=(), outputs=("delta",), progress=False):
    """delta (and optionally roller positions) as roller 1 advances from ``start`` to ``stop``.

    Parameters
    ----------
    model : EscalatorModel
    start, stop, step : float
        Range and step of roller 1's coordinate s0 on the undeformed guide. [m]
    rollers : sequence of int
        1-based roller numbers whose positions are stored (output ``roller_position``).
    outputs : sequence of str
        Names among ``delta``, ``s1``, ``roller_position``, ``closure_residual``.
    progress : bool
        Show progress on stderr (see :class:`vibkit.runtime.progress.Progress`); a compiled sweep of more
        than :data:`PROGRESS_CHUNK` configurations then runs in pieces, each warm-started from the last.

    Returns
    -------
    xarray.Dataset
        Dimension ``advance`` [m]; ``delta`` [m] always; attrs ``closure_residual_max`` [m].
    """
    advance = np.arange(start, stop, step)
    chain = model.chain
    want_pos = "roller_position" in outputs and len(rollers) > 0
    want_s1 = "s1" in outputs
    if want_pos or want_s1:
        # one configuration at a time: the positions are kept
        deltas = np.empty(advance.size)
        resid = np.empty(advance.size)
        pos = np.empty((advance.size, len(rollers), 2)) if want_pos else None
        s1 = np.empty(advance.size) if want_s1 else None
        idx = np.asarray(rollers, dtype=int) - 1
        guess = None
        bar = Progress(advance.size, "kinematic sweep", enabled=progress)
        for j, a in enumerate(advance):
            bar.update(j)
            conf = chain.configure(a, guess)
            guess = conf.delta
            deltas[j] = conf.delta
            resid[j] = conf.closure_residual
            if want_pos:
                pos[j] = conf.position[idx]
            if want_s1:
                s1[j] = chain.s_deformed(a, conf.delta)[0]
        bar.close()
    elif not progress or advance.size <= PROGRESS_CHUNK:
        deltas, resid = chain.sweep(advance)
    else:
        bar = Progress(advance.size, "kinematic sweep", enabled=True)
        deltas, resid = np.empty(advance.size), np.empty(advance.size)
        guess = None
        for i in range(0, advance.size, PROGRESS_CHUNK):
            sl = slice(i, min(i + PROGRESS_CHUNK, advance.size))
            deltas[sl], resid[sl] = chain.sweep(advance[sl], delta_guess=guess)
            guess = float(deltas[sl.stop - 1])
            bar.update(sl.stop)
        bar.close()
    data = {"delta": (("advance",), deltas)}
    if "closure_residual" in outputs:
        data["closure_residual"] = (("advance",), resid)
    if want_s1:
        data["s1"] = (("advance",), s1)
    coords = {"advance": advance}
    if want_pos:
        data["roller_position"] = (("advance", "roller", "axis"), pos)
        coords["roller"] = np.asarray(rollers)
        coords["axis"] = ["x", "z"]
    attrs = {
        "closure_residual_max": float(resid.max()),
        "closure_residual_max_units": "m",
        "advance_step_m": float(step),
    }
    return make_dataset(coords, data, attrs, model.scene)
