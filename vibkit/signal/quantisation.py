"""What a quantised record cannot resolve: the step of its levels and the spectral floor it sets.

A recorder that stores integer counts (or any fixed step ``q``) adds an error ``e = x_stored - x``
with ``|e| <= q / 2``.  When the signal moves over many steps and carries noise of at least about
``q / 2`` (dither), ``e`` is white with variance ``q**2 / 12`` (Widrow's model), so no spectral bin
can be resolved below that level.  Without dither -- a clean, noise-free tone -- ``e`` is a
deterministic function of the tone's phase: periodic, it is a *line spectrum* (the tone's harmonics,
aliased all over the band) of the same total variance, with almost nothing between the lines.  A
running median then sees the window's leakage, orders of magnitude below ``q**2 / 12``, and the
quantisation lines stand out as if they were harmonics.

:func:`quantisation_floor` bounds a floor from below by both cases: the white level ``q**2 / 12``,
and, for the part of that variance that the measured broadband floor does not account for, the peak
of one sinusoid of that variance (the worst case: all of the missing error power in one line).  A
record with noise above the step (every ordinary measurement) has its broadband floor above
``q**2 / 12`` and keeps its floor; a noise-free quantised record has no line weaker than its
quantisation error counted as evidence.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "MIN_SPAN_STEPS",
    "correlated_error_variance",
    "quantisation_floor",
    "quantisation_step",
    "signal_following_variance",
]

#: the levels' differences must be whole multiples of the step to this fraction of it
STEP_TOLERANCE = 1e-3
#: sub-divisions of the smallest difference between levels tried as the step
MAX_SUBDIVISIONS = 64
#: fewest steps a record must span for its grid to be read as a recorder's step (a tone of +-2 counts)
MIN_SPAN_STEPS = 4


def quantisation_step(x, *, max_samples=1 << 20, min_span=MIN_SPAN_STEPS) -> float:
    """Step ``q`` of the grid the samples lie on (``x = offset + n q``), or 0.0 when they lie on none.

    Parameters
    ----------
    x : array_like
        Samples as recorded (before scaling, filtering or resampling); non-finite values ignored. [x]
    max_samples : int, optional
        Only the first ``max_samples`` samples are examined.
    min_span : int, optional
        The samples must span at least this many steps: a record of two or three levels (a square
        wave, a logic signal) is the signal's own shape, not a recorder's resolution.

    Returns
    -------
    float
        The greatest common divisor of the differences between the distinct levels, to
        :data:`STEP_TOLERANCE` of it, found among the smallest difference divided by 1 ..
        :data:`MAX_SUBDIVISIONS`; 0.0 for continuous (floating-point) data, a constant record or one
        that spans fewer than ``min_span`` steps. [x]

    Examples
    --------
    >>> quantisation_step([0, 3, -2, 7, 1])
    1.0
    >>> quantisation_step([0.0, 0.25, 1.0, -0.5])
    0.25
    >>> quantisation_step([-1.0, 1.0, 1.0, -1.0])  # a square wave: two levels are its shape
    0.0
    >>> quantisation_step(np.sqrt([2.0, 3.0, 5.0, 7.0, 11.0, 13.0]))
    0.0
    """
    x = np.asarray(x, dtype=float).ravel()[: int(max_samples)]
    x = x[np.isfinite(x)]
    head = np.unique(x[:4096])
    if head.size >= 2 and _grid(head) == 0.0:
        return 0.0  # continuous data, decided on the first samples without sorting the record
    u = np.unique(x)
    q = _grid(u) if u.size >= 2 else 0.0
    return q if q > 0 and (u[-1] - u[0]) / q >= min_span - 0.5 else 0.0


def _grid(u):
    """Step of the sorted distinct levels ``u`` (at least two), or 0.0."""
    d = np.diff(u)
    d0 = float(d.min())
    # the differences carry the rounding of the levels themselves
    rounding = 16.0 * np.finfo(float).eps * float(np.max(np.abs(u))) / d0
    head = d[:4096]
    for m in range(1, MAX_SUBDIVISIONS + 1):
        q = d0 / m
        tol = STEP_TOLERANCE + rounding * m
        if tol > 0.05:
            break
        if np.all(np.abs(head / q - np.rint(head / q)) <= tol) and np.all(np.abs(d / q - np.rint(d / q)) <= tol):
            return q
    return 0.0


_K = np.arange(1, 257, dtype=float)
#: the terms' constant factors, as the formula below groups them (the same products, computed once: the noise
#: bisection of :func:`signal_following_variance` evaluates the sum 61 times per floor)
_TWO_PI2_K2 = 2.0 * np.pi**2 * _K**2
_MINUS_FOUR_PI2_K2 = -4.0 * np.pi**2 * _K**2
#: an exponent below which ``exp`` is exactly 0 in binary64 (its smallest subnormal is ``exp(-744.4)``), with margin
_EXP_ZERO_BELOW = -750.0
#: numpy sums a float array pairwise: halves down to blocks of 128, each block in 8 running sums
_PAIRWISE_BLOCK = 128


def _terms_kept(z):
    """How many of the sum's first terms can be nonzero at ``z = (s / q)**2 > 0``: ``exp(-4 pi**2 k**2 z)`` is exactly
    0 beyond, rounded up to whole rows of numpy's 8 running sums (at least 8, the full 256 past one block of 128), so
    that the sum of the kept terms adds the same numbers in the same order as the sum of all 256 (the rest only adds
    exact zeros): the same value bit for bit, without the exponentials that underflow (numpy's slow path: the
    bisection of :func:`signal_following_variance` evaluates the sum 61 times per floor)."""
    k = int(math.sqrt(_EXP_ZERO_BELOW / (-4.0 * math.pi**2 * z))) + 2
    n = max(8, -(-k // 8) * 8)
    return n if n <= _PAIRWISE_BLOCK else _K.size


def correlated_error_variance(step, noise_sd):
    """Variance of the part of the quantisation error that follows the signal, under Gaussian noise.

    The rounding error as a function of the input is the sawtooth
    ``e(x) = sum_k (-1)**k q / (pi k) sin(2 pi k x / q)``; Gaussian noise of standard deviation ``s``
    before the quantiser multiplies its ``k``-th term by ``exp(-2 pi**2 k**2 s**2 / q**2)`` once
    averaged over the noise (Widrow & Kollar, Quantization Noise, 2008, ch. 5 and 9).  What is left
    is a fixed function of the signal -- lines at its harmonics (aliased) -- of variance
    ``sum_k q**2 / (2 pi**2 k**2) exp(-4 pi**2 k**2 s**2 / q**2)``: ``q**2 / 12`` without noise,
    ``0.0015 q**2`` at ``s = 0.3 q``, ``3e-6 q**2`` at ``s = q / 2``.
    """
    q = float(step)
    if not q > 0:
        return 0.0
    z = (float(noise_sd) / q) ** 2
    if _MINUS_FOUR_PI2_K2[0] * z < _EXP_ZERO_BELOW:
        # every exponential is exactly 0 (the first term's is the largest): the sum of exact zeros, without them
        # (noise of more than 4.4 steps: nearly every step of the noise bisection on a finely quantised record)
        return 0.0
    n = _K.size if not z > 0 else _terms_kept(z)
    terms = q * q / _TWO_PI2_K2[:n] * np.exp(_MINUS_FOUR_PI2_K2[:n] * z)
    tail = q * q / (2.0 * np.pi**2 * _K[-1]) if z == 0 else 0.0
    return float(terms.sum() + tail)


def quantisation_floor(step, window, broadband, *, decimation=1.0) -> float:
    """Lowest per-bin floor of a Hann-type periodogram that a record with step ``step`` can resolve.

    Parameters
    ----------
    step : float
        Quantisation step of the recorded samples, in the units of the analysed ones (0: none). [x]
    window : ndarray
        The window of each periodogram segment (``|sum x w e^..|**2`` convention).
    broadband : float
        The measured broadband floor per bin (median level, noise mean), same convention.
    decimation : float, optional
        The analysed samples were low-pass filtered and decimated this many times after recording:
        the white quantisation noise per analysed sample is then ``q**2 / 12 / decimation``.

    Returns
    -------
    float
        The larger of the white level ``q**2 / 12 / m * sum w**2`` and the peak
        ``C * (sum w)**2 / 2`` of one line carrying all of the signal-following error variance ``C``
        (:func:`correlated_error_variance`), with the noise ``s`` solved from the broadband floor:
        ``s**2 + q**2 / 12 - C(s) = m * broadband / sum w**2`` per recorded sample.
    """
    q = float(step)
    if not q > 0:
        return 0.0
    m = max(float(decimation), 1.0)
    s1, s2 = float(np.sum(window)), float(np.sum(np.square(window)))
    c = signal_following_variance(q, m * float(broadband) / s2)
    return max(q * q / 12.0 / m * s2, c * s1 * s1 / 2.0)


def signal_following_variance(step, seen_variance):
    """:func:`correlated_error_variance` at the noise that a measured variance implies.

    Parameters
    ----------
    step : float
        Quantisation step. [x]
    seen_variance : float
        Variance per recorded sample of what is not signal (broadband floor, fit residual):
        ``s**2 + q**2 / 12 - C(s)``, solved for the analogue noise ``s``. [x**2]

    Returns
    -------
    float
        ``C(s)``; ``q**2 / 12`` when nothing is seen (a clean record). [x**2]
    """
    q = float(step)
    if not q > 0:
        return 0.0
    v = q * q / 12.0
    seen = float(seen_variance)
    lo, hi = 0.0, math.sqrt(max(seen, 0.0))
    if hi > 0:
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if mid * mid + v - correlated_error_variance(q, mid) > seen:
                hi = mid
            else:
                lo = mid
    return correlated_error_variance(q, lo)
