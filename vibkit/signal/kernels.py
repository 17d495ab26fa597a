"""The signal layer's compiled loops (numba), apart from the functions that call them.

:mod:`vibkit.signal.hampel`, :mod:`vibkit.signal.orders` and :mod:`vibkit.signal.ride` import this module
inside the function that needs a kernel, so that importing the signal package (every command that reads a
recording) does not import numba: a command that never filters, tracks or counts half-cycles never loads it.

* the Hampel filter's sorted sliding window: :func:`_insert`, :func:`_remove`, :func:`_replace`,
  :func:`_hampel_range`, :func:`_hampel_core` (used by :func:`vibkit.signal.hampel.hampel`);
* the Vold-Kalman filter's pentadiagonal solve :func:`_vk_solve` (:func:`vibkit.signal.orders.vold_kalman`);
* the half-cycle peaks of the ride metrics :func:`_half_cycle_peak_index`
  (:func:`vibkit.signal.ride.half_cycle_peaks`).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _insert(buf, count, value):
    j = count
    while j > 0 and buf[j - 1] > value:
        buf[j] = buf[j - 1]
        j -= 1
    buf[j] = value
    return count + 1


@numba.njit(cache=True, nogil=True)
def _remove(buf, count, value):
    # value is present (not NaN); find its position by binary search, shift left.
    lo = 0
    hi = count
    while lo < hi:
        mid = (lo + hi) // 2
        if buf[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    for j in range(lo, count - 1):
        buf[j] = buf[j + 1]
    return count - 1


@numba.njit(cache=True, nogil=True)
def _replace(buf, count, old, new):
    # Remove ``old`` (present) and insert ``new`` in one pass over the sorted buffer.
    lo = 0
    hi = count
    while lo < hi:
        mid = (lo + hi) // 2
        if buf[mid] < old:
            lo = mid + 1
        else:
            hi = mid
    j = lo
    if new > old:
        while j + 1 < count and buf[j + 1] < new:
            buf[j] = buf[j + 1]
            j += 1
    else:
        while j > 0 and buf[j - 1] > new:
            buf[j] = buf[j - 1]
            j -= 1
    buf[j] = new


@numba.njit(cache=True, nogil=True)
def _hampel_range(x, k, n_sigma, scale, fill_nan, y, outlier, med_out, sig_out, start, stop):
    n = x.shape[0]
    buf = np.empty(2 * k + 1)
    count = 0
    # Prime the window of sample ``start``: x[start-k .. start+k], truncated.
    for j in range(max(0, start - k), min(start + k + 1, n)):
        v = x[j]
        if v == v:
            count = _insert(buf, count, v)
    for i in range(start, stop):
        if i > start:
            add = i + k
            rem = i - k - 1
            va = x[add] if add < n else np.nan
            vr = x[rem] if rem >= 0 else np.nan
            if va == va and vr == vr:
                _replace(buf, count, vr, va)
            else:
                if vr == vr:
                    count = _remove(buf, count, vr)
                if va == va:
                    count = _insert(buf, count, va)
        xi = x[i]
        if count == 0:
            med_out[i] = np.nan
            sig_out[i] = np.nan
            y[i] = xi
            outlier[i] = False
            continue
        half = count // 2
        odd = count % 2 == 1
        if odd:
            m = buf[half]
        else:
            m = (buf[half - 1] + buf[half]) / 2.0
        # Deviations |buf - m| form two ascending runs: walking down from p-1 and up from p,
        # where p is the first index with buf[p] >= m (p <= half).  Merge them to rank ``half``.
        p = half
        while p > 0 and buf[p - 1] >= m:
            p -= 1
        left = p - 1
        right = p
        prev = 0.0
        cur = 0.0
        for _r in range(half + 1):
            if left >= 0 and (right >= count or m - buf[left] <= buf[right] - m):
                d = m - buf[left]
                left -= 1
            else:
                d = buf[right] - m
                right += 1
            prev = cur
            cur = d
        mad = cur if odd else (prev + cur) / 2.0
        s = scale * mad
        med_out[i] = m
        sig_out[i] = s
        if xi != xi:
            outlier[i] = False
            y[i] = m if fill_nan else xi
        elif abs(xi - m) > n_sigma * s:
            outlier[i] = True
            y[i] = m
        else:
            outlier[i] = False
            y[i] = xi


@numba.njit(cache=True, nogil=True, parallel=True)
def _hampel_core(x, k, n_sigma, scale, fill_nan, y, outlier, med_out, sig_out, n_chunks):
    n = x.shape[0]
    size = (n + n_chunks - 1) // n_chunks
    for c in numba.prange(n_chunks):
        start = c * size
        stop = min(n, start + size)
        if start < stop:
            _hampel_range(x, k, n_sigma, scale, fill_nan, y, outlier, med_out, sig_out, start, stop)


@numba.njit(cache=True, nogil=True)
def _vk_solve(y, r2):
    """Solve ``(I + r2 D^T D) a = y`` (D: second difference) by LDL^T of the pentadiagonal matrix.

    O(n), complex right-hand side; the same system as :func:`_vk_banded` and :func:`_vk_sparse`.
    """
    n = y.shape[0]
    dd = np.empty(n)
    p = np.zeros(n)
    q = np.zeros(n)
    z = np.empty(n, dtype=np.complex128)
    for i in range(n):
        # A[i, i], A[i, i-1], A[i, i-2] of I + r2 D^T D
        if i == 0 or i == n - 1:
            a_ii = 1.0 + r2
        elif i == 1 or i == n - 2:
            a_ii = 1.0 + 5.0 * r2
        else:
            a_ii = 1.0 + 6.0 * r2
        if i >= 2:
            q[i] = r2 / dd[i - 2]
        if i >= 1:
            e = -2.0 * r2 if (i == 1 or i == n - 1) else -4.0 * r2
            p[i] = (e - q[i] * p[i - 1] * dd[i - 2] if i >= 2 else e) / dd[i - 1]
        di = a_ii
        if i >= 1:
            di -= p[i] * p[i] * dd[i - 1]
        if i >= 2:
            di -= q[i] * q[i] * dd[i - 2]
        dd[i] = di
        zi = y[i]
        if i >= 1:
            zi -= p[i] * z[i - 1]
        if i >= 2:
            zi -= q[i] * z[i - 2]
        z[i] = zi
    out = np.empty(n, dtype=np.complex128)
    for i in range(n - 1, -1, -1):
        xi = z[i] / dd[i]
        if i + 1 < n:
            xi -= p[i + 1] * out[i + 1]
        if i + 2 < n:
            xi -= q[i + 2] * out[i + 2]
        out[i] = xi
    return out


@numba.njit(cache=True)
def _half_cycle_peak_index(x):  # pragma: no cover - compiled
    """Index of the largest |x| (first if tied) of every complete run of one sign, in one pass."""
    n = x.size
    out = np.empty(n, dtype=np.int64)  # up to one run per sample
    k = 0
    cur = 0.0  # sign of the current run (0 before the first non-zero sample)
    best = -1.0
    best_i = -1
    complete = False  # the current run started at a sign change (not at the record's start)
    for i in range(n):
        v = x[i]
        s = 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)
        if s != 0.0 and s != cur:
            if cur != 0.0 and complete:
                out[k] = best_i
                k += 1
            complete = cur != 0.0
            cur = s
            best = -1.0
        a = abs(v)
        if a > best:
            best = a
            best_i = i
    return out[:k]
