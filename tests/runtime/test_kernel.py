"""The model's kernels compiled without numba's reference counts (vibkit.runtime.kernel)."""

import sys

import numba
import numpy as np
import pytest

from vibkit.runtime.kernel import kernel


@kernel()
def _sum_rows(arrays, out):
    # arrays taken out of a tuple, as the model's kernels take theirs
    a, b = arrays
    for i in range(a.shape[0]):
        out[i] = a[i, 0] + b[i]
    return out


@kernel()
def _allocates(n):
    return np.empty(n)


def test_a_kernel_reads_and_writes_its_callers_arrays():
    a, b, out = np.arange(6.0).reshape(3, 2), np.array([10.0, 20.0, 30.0]), np.zeros(3)
    before = [sys.getrefcount(x) for x in (a, b, out)]
    for _ in range(1000):
        got = _sum_rows((a, b), out)
    assert got is out
    del got
    np.testing.assert_array_equal(out, [10.0, 22.0, 34.0])
    # no reference lost or leaked over a thousand calls
    assert [sys.getrefcount(x) for x in (a, b, out)] == before


def test_a_kernel_that_allocates_is_refused_at_compile_time():
    """The mistake a kernel without reference counts could make (an array nobody owns) does not
    compile: such a kernel has to be a plain numba.njit."""
    with pytest.raises(numba.core.errors.TypingError, match="returning of array passed into the function"):
        _allocates(3)
