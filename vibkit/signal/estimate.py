"""Frequency estimation below the bin width, with Cramer-Rao standard deviations.

Two estimators:

* :func:`interpolated_dft` (fast): Aboutanios-Mulgrew iterative interpolation of the DFT at half-bin
  offsets around the peak; O(N) after one FFT.  Single tone.
* :func:`harmonic_ls` (precise): nonlinear least squares of a harmonic series
  ``c + sum_h A_h cos(2 pi h f0 t + phi_h)`` by Gauss-Newton on all parameters.

Both return a :class:`FrequencyEstimate` whose ``sigma_hz`` is the Cramer-Rao bound evaluated with
the fitted amplitudes and residual noise (white Gaussian noise model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._checks import as_signal, check_band, check_fs, check_positive_int, fill_nan

__all__ = [
    "FrequencyEstimate",
    "crb_single_tone",
    "crb_harmonic",
    "interpolated_dft",
    "harmonic_ls",
]

# Variance of the Aboutanios-Mulgrew estimator relative to the CRB (two or more iterations).
AM_EFFICIENCY = 1.0147


def crb_single_tone(n, fs, snr):
    """Cramer-Rao standard deviation of the frequency of one real sinusoid in white noise.

    Parameters
    ----------
    n : int
        Number of samples.
    fs : float
        Sampling frequency. [Hz]
    snr : float
        ``A**2 / (2 sigma**2)``: sine power over noise variance (linear, not dB).

    Returns
    -------
    float
        Standard deviation bound. [Hz]

    Notes
    -----
    ``var(f) >= 12 fs**2 / ((2 pi)**2 snr N (N**2 - 1))`` (Kay 1993, eq. 3.41).  The often quoted
    constant 6 belongs to a complex exponential with ``snr = |A|**2 / sigma**2``; for a real sine
    with ``snr = A**2 / (2 sigma**2)`` it is 12, which Monte Carlo runs of the exact least-squares
    estimator confirm.

    References
    ----------
    S. M. Kay, Fundamentals of Statistical Signal Processing: Estimation Theory, 1993, sec. 3.7.
    """
    n = float(n)
    return float(np.sqrt(12.0 * fs**2 / ((2.0 * np.pi) ** 2 * snr * n * (n * n - 1.0))))


def crb_harmonic(n, fs, amplitudes, noise_std):
    """Cramer-Rao standard deviation of the fundamental of a harmonic series in white noise.

    Parameters
    ----------
    n : int
        Number of samples.
    fs : float
        Sampling frequency. [Hz]
    amplitudes : array_like
        ``A_k`` of harmonics ``k = 1 .. K``. [x]
    noise_std : float
        Noise standard deviation. [x]

    Returns
    -------
    float
        Standard deviation bound. [Hz]

    Notes
    -----
    ``var(f0) >= 12 fs**2 / ((2 pi)**2 N (N**2 - 1) sum_k k**2 A_k**2 / (2 sigma**2))``.

    References
    ----------
    P. Stoica, R. Moses, Spectral Analysis of Signals, 2005, sec. 4.
    """
    a = np.asarray(amplitudes, dtype=float)
    k = np.arange(1, a.size + 1)
    eff = float(np.sum(k**2 * a**2) / (2.0 * float(noise_std) ** 2))
    return crb_single_tone(n, fs, eff)


@dataclass(frozen=True)
class FrequencyEstimate:
    """Result of a frequency estimator.

    Attributes
    ----------
    frequency_hz : float
        Estimated (fundamental) frequency. [Hz]
    sigma_hz : float
        Standard deviation expected for this estimator: the CRB with fitted amplitudes and residual
        noise, times the estimator's known efficiency (1 for least squares). [Hz]
    crb_hz : float
        Cramer-Rao bound with fitted amplitudes and residual noise. [Hz]
    amplitudes : ndarray
        Amplitudes of harmonics 1..K (one entry for a single tone). [x]
    phases : ndarray
        Cosine phases at the first sample. [rad]
    noise_std : float
        Residual standard deviation. [x]
    snr_db : float
        ``10 log10(sum A_k**2 / 2 / noise_std**2)``. [dB]
    n_samples : int
    fs : float
        [Hz]
    method : str
    offset : float
        Fitted constant. [x]
    warnings : list of str
    """

    frequency_hz: float
    sigma_hz: float
    crb_hz: float
    amplitudes: np.ndarray
    phases: np.ndarray
    noise_std: float
    snr_db: float
    n_samples: int
    fs: float
    method: str
    offset: float = 0.0
    warnings: list = field(default_factory=list)


def _prepare(x, fs, nan_policy):
    fs = check_fs(fs)
    x = as_signal(x, min_samples=8)
    if x.ndim != 1:
        raise ValueError(f"Parameter x must be 1-D, got shape {x.shape}.")
    return fill_nan(x, nan_policy=nan_policy), fs


def expj(theta):
    """``exp(1j * theta)`` for real ``theta`` [rad], as ``cos(theta) + 1j sin(theta)`` written into one complex
    array: numpy's complex exponential of a purely imaginary argument gives these values (where its cosine and
    sine are the C library's, bit for bit) at twice the cost."""
    z = np.empty(np.shape(theta), dtype=complex)
    np.cos(theta, out=z.real)
    np.sin(theta, out=z.imag)
    return z


def _dtft(x, nu):
    """DTFT of ``x`` at normalised frequency ``nu`` [cycles/sample]."""
    # exp(-2j pi nu n): the imaginary products of ``-2j pi nu n`` (its real ones are zeros)
    return np.dot(x, expj((-2j * np.pi * nu).imag * np.arange(x.size)))


def _peak_bin(x, fs, band):
    n = x.size
    spec = np.abs(np.fft.rfft(x - x.mean()))
    f = np.arange(spec.size) * fs / n
    lo, hi = band
    sel = np.flatnonzero((f >= lo) & (f <= hi))
    sel = sel[(sel >= 1) & (sel < spec.size - 1)]
    if sel.size == 0:
        raise ValueError(
            f"Parameter band=({lo:g}, {hi:g}) Hz holds no interior DFT bin of a {n / fs:.4g} s record "
            f"(bin width {fs / n:.4g} Hz); widen the band or give a longer record."
        )
    return int(sel[np.argmax(spec[sel])])


def _fit_tone(x, fs, f):
    """Linear LS of offset + one cosine at ``f``: (offset, amplitude, phase, residual std)."""
    n = x.size
    t = np.arange(n) / fs
    w = 2.0 * np.pi * f * t
    m = np.column_stack([np.ones(n), np.cos(w), np.sin(w)])
    coef, *_ = np.linalg.lstsq(m, x, rcond=None)
    r = x - m @ coef
    amp = float(np.hypot(coef[1], coef[2]))
    phase = float(np.arctan2(-coef[2], coef[1]))
    dof = max(n - 4, 1)
    return float(coef[0]), amp, phase, float(np.sqrt(r @ r / dof))


def _interpolated_frequency(x, fs, band, f_guess, iterations):
    """The frequency of :func:`interpolated_dft` alone (checked ``x`` and ``fs``), without its tone fit: what a
    caller that only starts another estimator from it needs (the fit is a least squares of the record's length)."""
    n = x.size
    xc = x - x.mean()
    if f_guess is not None:
        k = float(f_guess) * n / fs
        if not 0.0 < k < n / 2.0:
            raise ValueError(f"Parameter f_guess={f_guess!r} must lie in (0, fs/2 = {fs / 2:g}) Hz.")
        k0, delta = int(round(k)), k - round(k)
    else:
        b = check_band(band, fs) if band is not None else (fs / n, fs / 2.0)
        k0, delta = _peak_bin(xc, fs, b), 0.0
    for _ in range(iterations):
        xp = _dtft(xc, (k0 + delta + 0.5) / n)
        xm = _dtft(xc, (k0 + delta - 0.5) / n)
        step = 0.5 * float(np.real((xp + xm) / (xp - xm)))
        delta += float(np.clip(step, -0.5, 0.5))
    return (k0 + delta) * fs / n


def interpolated_frequency(x, fs, *, band=None, f_guess=None, iterations=3, nan_policy="raise"):
    """The frequency :func:`interpolated_dft` gives [Hz], bit for bit, without its single-tone fit (amplitude,
    noise and sigma): for a start of :func:`harmonic_ls`, which fits the whole family itself."""
    x, fs = _prepare(x, fs, nan_policy)
    iterations = check_positive_int(iterations, "iterations")
    return float(_interpolated_frequency(x, fs, band, f_guess, iterations))


def interpolated_dft(x, fs, *, band=None, f_guess=None, iterations=3, nan_policy="raise"):
    """Fast single-tone frequency estimate below the bin width (Aboutanios-Mulgrew).

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    band : (float, float), optional
        Search band for the DFT peak. [Hz]  Default: whole spectrum without DC.
    f_guess : float, optional
        Start here instead of at the DFT peak (within half a bin of the tone). [Hz]
    iterations : int, optional
        Interpolation passes; 2 reach the asymptotic efficiency.
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    FrequencyEstimate
        ``sigma_hz = sqrt(1.0147) * crb_hz``.

    Notes
    -----
    With ``X(+-) = DTFT(x)`` at ``k + delta +- 1/2`` bins, each pass updates
    ``delta += Re[(X+ + X-) / (X+ - X-)] / 2``.  No window: a strong component within a few bins
    biases the estimate; for harmonic series use :func:`harmonic_ls`.

    References
    ----------
    E. Aboutanios, B. Mulgrew, IEEE Trans. Signal Process. 53 (2005) 1237-1242.
    """
    x, fs = _prepare(x, fs, nan_policy)
    iterations = check_positive_int(iterations, "iterations")
    n = x.size
    f = _interpolated_frequency(x, fs, band, f_guess, iterations)
    offset, amp, phase, noise = _fit_tone(x, fs, f)
    snr = amp**2 / (2.0 * noise**2) if noise > 0 else np.inf
    crb = crb_single_tone(n, fs, snr) if np.isfinite(snr) else 0.0
    warn = []
    if snr * n < 50.0:  # integrated SNR below 17 dB: threshold region of DFT-based estimators
        warn.append(f"integrated SNR {10 * np.log10(max(snr * n, 1e-300)):.1f} dB is below 17 dB; outliers likely")
    return FrequencyEstimate(
        frequency_hz=float(f),
        sigma_hz=float(np.sqrt(AM_EFFICIENCY) * crb),
        crb_hz=float(crb),
        amplitudes=np.array([amp]),
        phases=np.array([phase]),
        noise_std=noise,
        snr_db=float(10 * np.log10(snr)) if snr > 0 else -np.inf,
        n_samples=n,
        fs=fs,
        method="interpolated-dft",
        offset=offset,
        warnings=warn,
    )


#: rows of the harmonic basis :func:`harmonic_ls` builds at a time (its sums accumulate over blocks of this many
#: samples: 16 k rows of 12 columns are 1.5 MB, whatever the record's length; 64 k-row blocks woke BLAS's threads,
#: which cost 3 times the products' own time on a busy 2-core machine)
LS_BLOCK_ROWS = 1 << 14
#: a record of up to this many samples keeps its blocks' ``exp(1j omega t)`` between :func:`harmonic_ls`'s two passes
#: over them at one frequency (the same values, not taken twice: the cosines and sines were most of a pass; 64 MB
#: complex at most)
LS_KEEP_FUNDAMENTAL = 1 << 22


def _harmonic_basis(t, omega, n_harmonics, extra=0, z1=None):
    """Columns ``1, cos(k w t), sin(k w t)`` (k = 1..K) in a Fortran array, plus ``extra`` spare; ``z1``: the
    fundamental's ``exp(1j omega t)`` where the caller has it (the same values: not taken again)."""
    m = np.empty((t.size, 2 * n_harmonics + 1 + extra), order="F")
    m[:, 0] = 1.0
    if z1 is None:
        z1 = expj((1j * omega).imag * t)  # exp(1j omega t)
    z = z1.copy()
    for k in range(n_harmonics):
        if k:
            z *= z1
        m[:, 1 + k] = z.real
        m[:, 1 + n_harmonics + k] = z.imag
    return m


def _ls(m, x):
    g = m.T @ m
    rhs = m.T @ x
    try:
        return np.linalg.solve(g, rhs)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(m, x, rcond=None)[0]


def harmonic_ls(x, fs, *, f_guess, n_harmonics=5, max_iter=20, nan_policy="raise"):
    """Precise estimate of the fundamental of a harmonic series by nonlinear least squares.

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    f_guess : float
        Starting fundamental, within about ``1 / (4 K T)`` of the truth (``K`` harmonics,
        ``T`` record length) -- e.g. from :func:`vibkit.signal.find_fundamental`. [Hz]
    n_harmonics : int, optional
        ``K``; harmonics above Nyquist are an error.
    max_iter : int, optional
        Gauss-Newton iterations at most.
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    FrequencyEstimate
        ``sigma_hz = crb_hz`` from :func:`crb_harmonic` with the fitted amplitudes and residual
        standard deviation.

    Raises
    ------
    ValueError
        Bad arguments, harmonics above Nyquist.

    Notes
    -----
    Model ``x(t) = c + sum_{k=1}^{K} a_k cos(k w t') + b_k sin(k w t')`` with ``t'`` centred on
    the record (decorrelates frequency and phases).  Gauss-Newton on ``(c, a, b, w)`` with the
    analytic Jacobian; a step that raises the cost is halved until it does not.

    References
    ----------
    P. Stoica, R. Moses, Spectral Analysis of Signals, 2005.
    """
    x, fs = _prepare(x, fs, nan_policy)
    kmax = check_positive_int(n_harmonics, "n_harmonics")
    max_iter = check_positive_int(max_iter, "max_iter")
    try:
        f0 = float(f_guess)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter f_guess={f_guess!r} must be a positive frequency [Hz].") from None
    if not np.isfinite(f0) or f0 <= 0:
        raise ValueError(f"Parameter f_guess={f_guess!r} must be a positive frequency [Hz].")
    if kmax * f0 >= fs / 2.0:
        raise ValueError(
            f"Parameter n_harmonics={kmax} puts harmonic {kmax} x {f0:g} Hz above Nyquist ({fs / 2:g} Hz)."
        )
    n = x.size
    duration = n / fs
    if f0 * duration < 2.0:
        raise ValueError(
            f"Parameter x is {duration:.4g} s long, under two periods of {f0:g} Hz; expected >= {2 / f0:.4g} s."
        )
    h = np.arange(1, kmax + 1)
    # the sums the least squares need (normal equations, cost) accumulated over blocks of rows: the basis is
    # never held whole (it was 12 columns of the record's length: 1.3 GB for 8 h at 200 Hz); a record of one
    # block does exactly what the whole-matrix form did (adding to zeros is exact)
    blocks = [(i, min(n, i + LS_BLOCK_ROWS)) for i in range(0, n, LS_BLOCK_ROWS)]
    n_col = 2 * kmax + 1

    def basis(i, j, omega, z1=None, keep=None):
        t = (np.arange(i, j) - (n - 1) / 2.0) / fs  # elementwise as np.arange(n)[i:j] would give
        if keep is not None:  # exp(1j omega t) kept for the second pass (:data:`LS_KEEP_FUNDAMENTAL`)
            keep.append(expj((1j * omega).imag * t))
            z1 = keep[-1]
        return t, _harmonic_basis(t, omega, kmax, extra=1, z1=z1)

    keep_z1 = 1 < len(blocks) and n <= LS_KEEP_FUNDAMENTAL

    def fit_at(omega):
        """Linear fit at omega: its coefficients and cost, and the Gauss-Newton sums J^T J and J^T r there (the
        columns of the basis and d model / d omega), from a second pass over the blocks once the fit is known."""
        g, rhs, kept, z1 = np.zeros((n_col, n_col)), np.zeros(n_col), None, [] if keep_z1 else None
        for i, j in blocks:
            t, full = basis(i, j, omega, keep=z1)
            m = full[:, :-1]
            g += m.T @ m
            rhs += m.T @ x[i:j]
            if len(blocks) == 1:
                kept = t, full  # one block: the basis is reused below, as the whole-matrix form did
        try:
            coef = np.linalg.solve(g, rhs)
        except np.linalg.LinAlgError:
            coef = (
                np.linalg.lstsq(kept[1][:, :-1], x, rcond=None)[0]
                if kept is not None
                else np.linalg.lstsq(g, rhs, rcond=None)[0]
            )
        a, b = coef[1 : kmax + 1], coef[kmax + 1 :]
        cost, gj, jtr, last = 0.0, np.zeros((n_col + 1, n_col + 1)), np.zeros(n_col + 1), None
        for ib, (i, j) in enumerate(blocks):
            t, jac = kept if kept is not None else basis(i, j, omega, None if z1 is None else z1[ib])
            m = jac[:, :-1]
            r = x[i:j] - m @ coef
            # one block: r @ r as the whole-matrix form; several: numpy's pairwise sum (BLAS's threaded dot costs
            # milliseconds a call on a busy machine, hundreds of calls per fit)
            cost += float(r @ r) if kept is not None else float(np.sum(r * r))
            jac[:, -1] = t * (m[:, kmax + 1 :] @ (-(a * h)) + m[:, 1 : kmax + 1] @ (b * h))
            gj += jac.T @ jac
            jtr += jac.T @ r
            last = (jac, r) if kept is not None else None
        return coef, cost, (gj, jtr, last)

    omega = 2.0 * np.pi * f0
    coef, cost, sums = fit_at(omega)
    iterations = 0
    for iterations in range(1, max_iter + 1):  # noqa: B007 (the count is read after the loop)
        g, jtr, last = sums
        try:
            delta = np.linalg.solve(g, jtr)
            var_omega = float(np.linalg.inv(g)[-1, -1]) * cost / max(n - (n_col + 1), 1)
        except np.linalg.LinAlgError:
            delta = (
                np.linalg.lstsq(last[0], last[1], rcond=None)[0]
                if last is not None
                else np.linalg.lstsq(g, jtr, rcond=None)[0]
            )
            var_omega = 0.0
        step = float(delta[-1])
        if abs(step) <= 1e-3 * np.sqrt(var_omega) or abs(step) < 1e-13 * omega:
            omega += step
            coef, cost, sums = fit_at(omega)
            break
        accepted = False
        for _ in range(30):
            cand = omega + step
            coef_c, cost_c, sums_c = fit_at(cand)
            if cost_c <= cost:
                accepted = True
                break
            step /= 2.0
        if not accepted:
            break
        omega, coef, cost, sums = cand, coef_c, cost_c, sums_c
    a = coef[1 : kmax + 1]
    b = coef[kmax + 1 :]
    amps = np.hypot(a, b)
    f = omega / (2.0 * np.pi)
    phases_c = np.arctan2(-b, a)
    phases = np.angle(np.exp(1j * (phases_c - h * omega * (n - 1) / 2.0 / fs)))
    noise = float(np.sqrt(cost / max(n - (2 * kmax + 2), 1)))
    warn = []
    if noise > 0:
        crb = crb_harmonic(n, fs, amps, noise)
        snr = float(np.sum(amps**2) / 2.0 / noise**2)
    else:
        crb, snr = 0.0, np.inf
    if abs(f - f0) > 1.0 / (2.0 * duration):
        warn.append(f"estimate {f:.6g} Hz moved more than half a bin from the guess {f0:.6g} Hz; check the guess")
    if iterations >= max_iter:
        warn.append(f"Gauss-Newton stopped after max_iter={max_iter} iterations")
    return FrequencyEstimate(
        frequency_hz=float(f),
        sigma_hz=float(crb),
        crb_hz=float(crb),
        amplitudes=amps,
        phases=phases,
        noise_std=noise,
        snr_db=float(10 * np.log10(snr)) if snr > 0 else -np.inf,
        n_samples=n,
        fs=fs,
        method="harmonic-ls",
        offset=float(coef[0]),
        warnings=warn,
    )
