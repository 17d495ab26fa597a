"""Where a roller of a chain with unequal links crosses a place of the guide: Newton's method, compiled.

With equal links the crossing values of one configuration are those of every roller, relabelled
(:meth:`vibkit.model.chain.Chain.crossing_table`); with unequal links each pair (roller, place) needs
its own value of s0_1. Each is found by Newton's method on f(s0_1) = s0_k(s0_1) - b with
df/ds0_1 = gamma_k from the velocity recursion, the chain closed from the last solve's delta
(the tensioner moves by millimetres over a loop, so that is always a close guess), from the
uniform chain's value shifted as the last pair's was.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .chain import fill_partials, sensitivity, solve_closure, velocity_coefficients, walk_arrays

__all__ = ["crossing_values"]

MAX_ITERATIONS = 30
TOLERANCE = 1e-13  # [m] on s0_k - b, as the interpreted search it replaces


@nb.njit(cache=True, error_model="numpy")
def crossing_values(tab, p0, lt, pitches, n, tol, rollers, places, starts, delta0, out):
    """For each i: the s0_1 in [0, p0) near ``starts[i]`` at which roller ``rollers[i]`` (from 0) sits at
    undeformed coordinate ``places[i]`` (fills ``out``). Returns the index of a pair whose chain
    could not be closed, or -1."""
    s0, kk, lam, xs, zs, part, alpha, beta = walk_arrays(n)
    jac = np.empty((n, 2))
    gam = np.empty(n)
    d = delta0
    shift = 0.0  # the last pair's value less its start: neighbouring rollers on one place shift alike
    for i in range(rollers.size):
        k = rollers[i]
        b = places[i]
        x = starts[i] + shift
        for _ in range(MAX_ITERATIONS):
            d, _, st = solve_closure(tab, p0, lt, x, d, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol)
            if st != 0:
                return i
            f = s0[k] - b + 0.5 * p0
            f = f - p0 * math.floor(f / p0) - 0.5 * p0
            if abs(f) < TOLERANCE:
                break
            fill_partials(tab, p0, s0, kk, lam, d, n + 1, part)
            sensitivity(part, xs, zs, n + 1, alpha, beta)
            velocity_coefficients(part, xs, zs, n, alpha, beta, jac, gam)
            x -= f / gam[k]
        shift = x - starts[i]
        out[i] = x - p0 * math.floor(x / p0)
    return -1
