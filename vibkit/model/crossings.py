"""Where a roller of a chain with unequal links crosses a place of the guide: Newton's method, compiled.

With equal links the crossing values of one configuration are those of every roller, relabelled
(:meth:`vibkit.model.chain.Chain.crossing_table`); with unequal links each pair (roller, place) needs
its own value of s0_1. Each is found by Newton's method on f(s0_1) = s0_k(s0_1) - b with
df/ds0_1 = ds0_k/ds0_1, the chain closed run by run (:mod:`vibkit.model.runs`, the exact closure)
from the last solve's delta moved along its slope (the tensioner moves by millimetres over a loop, so
that is always a close guess), from the uniform chain's value shifted as the last pair's was.
"""

from __future__ import annotations

import math

from ..runtime.kernel import kernel
from .guide import S0, local_map
from .runs import (
    A_GHOST,
    A_RUNS,
    R_ALPHA,
    R_BETA,
    R_FIRST,
    R_LAM,
    R_LAST,
    R_SEG,
    R_STEP,
    R_WRAPS,
    roller_s0,
    run_close,
)

__all__ = ["crossing_values"]

MAX_ITERATIONS = 30
TOLERANCE = 1e-13  # [m] on s0_k - b, as the interpreted search it replaces


@kernel()
def crossing_values(tab, p0, pitches, n, tol, rstep, rnext, runs, aux, rollers, places, starts, delta0, out):
    """For each i: the s0_1 in [0, p0) near ``starts[i]`` at which roller ``rollers[i]`` (from 0) sits at
    undeformed coordinate ``places[i]`` (fills ``out``). ``rstep`` ... ``aux``: the run-by-run
    closure's data (:func:`vibkit.model.runs.run_steps`, :func:`vibkit.model.runs.next_other`, scratch).
    Returns the index of a pair whose chain could not be closed, or -1."""
    d = delta0
    shift = 0.0  # the last pair's value less its start: neighbouring rollers on one place shift alike
    x_last = starts[0]  # where the last closure was, and its slope ddelta/ds0_1 there: the next guess
    c = 0.0
    for i in range(rollers.size):
        k = rollers[i]
        b = places[i]
        x = starts[i] + shift
        for _ in range(MAX_ITERATIONS):
            d, _, st = run_close(tab, p0, x, d + c * (x - x_last), pitches, n, tol, rstep, rnext, runs, aux)
            if st != 0:
                return i
            nr = int(aux[A_RUNS])
            g = nr - 1
            c = (aux[A_GHOST] - runs[g, R_ALPHA]) / (runs[g, R_BETA] - aux[A_GHOST + 1])
            x_last = x
            r = 0
            while r < nr - 1 and runs[r, R_LAST] < k:
                r += 1
            seg = int(runs[r, R_SEG])
            lam = runs[r, R_LAM] + (k - runs[r, R_FIRST]) * runs[r, R_STEP]
            s0k = roller_s0(tab, p0, seg, lam, runs[r, R_WRAPS], d)
            f = s0k - b + 0.5 * p0
            f = f - p0 * math.floor(f / p0) - 0.5 * p0
            if abs(f) < TOLERANCE:
                break
            # ds0_k/ds0_1 from the run's rate, lam-dot = alpha s-dot + beta delta-dot, and delta-dot = c s-dot
            _, ls, ld, _, _ = local_map(tab, seg, s0k - runs[r, R_WRAPS] * p0 - tab[seg, S0], d)
            x -= f / ((runs[r, R_ALPHA] + runs[r, R_BETA] * c - ld * c) / ls)
        shift = x - starts[i]
        out[i] = x - p0 * math.floor(x / p0)
    return -1
