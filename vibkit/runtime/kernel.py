"""How vibkit compiles the model's kernels: numba's ``njit``, cached, numpy's error model, and without the
runtime's reference counts.

Numba keeps a reference count on every array it handles (its runtime, NRT), and a compiled function that
takes arrays out of a tuple (the model's parameters, work arrays and tables travel as tuples of arrays)
counts each one up on the way in and down on the way out, with an atomic instruction. On this project's
2-core virtual machines those atomic operations took 42-45 % of the CPU time of the 44 s forward run
(``perf`` on the worn chain: most samples on the two instructions after ``lock incq`` and ``lock decq`` in
``NRT_incref`` and ``NRT_decref``); numba's passes that remove needless counts left them in place (85
call sites of ``NRT_incref`` in the compiled right-hand side).

:func:`kernel` compiles with ``_nrt=False``: no reference counts at all. Such a function cannot allocate
an array (numba refuses to compile it, so the mistake cannot slip through) and cannot return a view; the
arrays it touches are its callers', alive for the whole call. Kernels that allocate (work arrays, the
integrator's stages) keep ``numba.njit``. ``_nrt`` is numba's switch for its runtime (an option of
``numba.jit`` since the runtime came in, kept for numba's developers); it is not in numba's user
documentation, so :func:`kernel` is the one place that names it, and ``tests/runtime/test_kernel.py`` fails
if it stops doing what this module relies on. ``docs/explanation/performance.md`` has the
measurement.
"""

from __future__ import annotations

import numba as nb

__all__ = ["kernel"]


def kernel(**options):
    """``numba.njit`` for a model kernel that allocates no array: cached, numpy's error model (a division
    by zero gives inf or nan, as numpy does), no reference counting; ``options`` (``inline``, ``nogil``)
    passed on."""
    return nb.njit(cache=True, error_model="numpy", _nrt=False, **options)
