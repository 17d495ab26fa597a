"""Frequency weightings of whole-body vibration (ISO 2631-1, ISO 2631-4, ISO 8041-1) as digital filters.

A weighting is a cascade of four analogue sections (ISO 2631-1:1997 Annex A, ISO 8041-1:2017
clause 5.6 / Table 3), with ``s = j 2 pi f`` and ``w_i = 2 pi f_i``:

* band-limiting high-pass (2nd-order Butterworth, ``Q1 = 1/sqrt(2)``):
  ``Hh = s^2 / (s^2 + w1 s / Q1 + w1^2)``
* band-limiting low-pass (2nd-order Butterworth, ``Q2 = 1/sqrt(2)``):
  ``Hl = w2^2 / (s^2 + w2 s / Q2 + w2^2)``
* acceleration-velocity transition:
  ``Ht = (1 + s / w3) / (1 + s / (Q4 w4) + s^2 / w4^2)``
* upward step:
  ``Hs = (s^2 + w5 s / Q5 + w5^2) / (s^2 + w6 s / Q6 + w6^2)``  (gain ``(f5/f6)^2`` at 0 Hz, 1 above)

and ``W(f) = K Hh Hl Ht Hs``.  An infinite ``f3``, ``f4`` or ``f5 = f6`` removes that factor.

Sources (the ISO texts themselves were not available to us):

* the parameter table: ISO 8041 Table 3 as reproduced in the Larson Davis HVM200 Reference Manual
  (IHVM200.01 Rev C, Table 3.1 "Parameters and transfer functions of the frequency weightings
  (source: ISO 8041)", with its notes that the Wb and Wh values there are the exact ones that
  ISO 2631-4 and ISO 5349-1 round); the same manual's MATLAB listing fixes the form of the upward
  step used above (``B4 = [1/w5^2, 1/(Q5 w5), 1] w5^2/w6^2``, ``A4 = [1/w6^2, 1/(Q6 w6), 1]``);
* checks of the analytic response (``tests/signal/test_signal_weighting.py``): the values at the
  ISO 8041 reference frequency 15.915 Hz (100 rad/s) as listed by ZETLAB (zetlab.com, "Frequency
  weighting functions": Wb 0.8126, Wc 0.5145, Wd 0.1261, We 0.06287, Wj 1.019) and ISO 2631-1 Table 3
  (Wk and Wd at the one-third-octave centres) as transcribed in public code.

Digital realisation.  Each section is mapped by the bilinear transform, pre-warped at its own
characteristic frequency (``f1``, ``f2``, ``f4``, ``sqrt(f5 f6)``).  The bilinear map compresses
the whole analogue axis into ``[0, fs/2)``, so its error grows towards Nyquist: at a rate of
:data:`INTERNAL_RATE_HZ` (2000 Hz) and above, the cascade matches the analytic magnitude within
0.031 dB from 0.5 to 80 Hz (0.0073 dB at 4096 Hz; the error falls as ``1/fs^2``; Wf is compared
down to -120 dB, below which it is of no use).  Below that rate :func:`frequency_weighting`
**oversamples internally** by the integer ``L = ceil(2000 / fs)``: the record is interpolated with a
zero-phase Kaiser-windowed FIR (flat within 0.001 dB to 0.85 of the original Nyquist, zero phase,
so only the weighting's own phase is applied), filtered at ``L fs``, and every L-th sample kept (no
decimation filter is needed: the interpolated record has nothing above the original Nyquist and a
linear filter creates nothing new).  So at ``fs = 200 Hz`` the result matches the analytic response
within 0.1 dB to 80 Hz (0.8 of Nyquist), and the band-limiting low-pass at 100 Hz, which is then
above what the record can hold, still shapes 50-85 Hz exactly as the standard says; content at and
above 0.85 Nyquist is attenuated by the interpolation filter (a sample rate of at least 2.5 times the
highest frequency of interest is what ISO 8041 instruments use).  :func:`frequency_weighting_sos`
gives the plain cascade at a rate the caller chooses, for use with ``scipy.signal.sosfilt``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from ._checks import as_signal, check_fs, fill_nan

__all__ = [
    "INTERNAL_RATE_HZ",
    "WEIGHTINGS",
    "Weighting",
    "frequency_weighting",
    "frequency_weighting_response",
    "frequency_weighting_sos",
    "get_weighting",
]

#: lowest rate at which the weighting cascade is run; slower records are oversampled to reach it [Hz]
INTERNAL_RATE_HZ = 2000.0
_SQRT_HALF = 1.0 / math.sqrt(2.0)


@dataclass(frozen=True, kw_only=True)
class Weighting:
    """Parameters of one frequency weighting (ISO 8041 Table 3 form).

    Attributes
    ----------
    name : str
        ``"Wk"``, ``"Wd"`` ...
    f1, f2 : float
        Band-limiting high-pass and low-pass corner frequencies. [Hz]
    f3, f4 : float
        Acceleration-velocity transition (``math.inf`` when absent). [Hz]
    q4 : float
        Quality factor of the transition. [-]
    f5, f6 : float
        Upward step (``math.inf`` when absent). [Hz]
    q5, q6 : float
        Quality factors of the step. [-]
    k : float
        Gain. [-]
    q1, q2 : float
        Quality factors of the band limits (``1/sqrt(2)``: Butterworth). [-]
    use : str
        What the standard uses it for.
    """

    name: str
    f1: float
    f2: float
    f3: float
    f4: float
    q4: float
    f5: float
    q5: float
    f6: float
    q6: float
    k: float
    q1: float = _SQRT_HALF
    q2: float = _SQRT_HALF
    use: str = ""

    def __post_init__(self):
        for key in ("f1", "f2", "f3", "f4", "q4", "f5", "q5", "f6", "q6", "k", "q1", "q2"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float)) and v > 0 and not math.isnan(v)):
                raise ValueError(f"Weighting {self.name}: parameter {key}={v!r} must be a positive number.")
        if not self.f2 > self.f1:
            raise ValueError(f"Weighting {self.name}: f2={self.f2} must exceed f1={self.f1} [Hz].")

    def analog_sections(self):
        """The analogue sections as ``[(b, a), ...]`` polynomials in ``s`` (highest power first), with
        the frequency [Hz] at which each is pre-warped in the bilinear transform."""
        tp = 2.0 * math.pi
        w1, w2 = tp * self.f1, tp * self.f2
        out = [
            ([1.0, 0.0, 0.0], [1.0, w1 / self.q1, w1 * w1], self.f1),
            ([w2 * w2], [1.0, w2 / self.q2, w2 * w2], self.f2),
        ]
        if math.isfinite(self.f4):
            w4 = tp * self.f4
            b = [w4 * w4 / (tp * self.f3), w4 * w4] if math.isfinite(self.f3) else [w4 * w4]
            out.append((b, [1.0, w4 / self.q4, w4 * w4], self.f4))
        if math.isfinite(self.f5) and math.isfinite(self.f6):
            w5, w6 = tp * self.f5, tp * self.f6
            out.append(([1.0, w5 / self.q5, w5 * w5], [1.0, w6 / self.q6, w6 * w6], math.sqrt(self.f5 * self.f6)))
        return out


_INF = math.inf
#: ISO 8041 Table 3 (Larson Davis HVM200 manual, Table 3.1); Wb also ISO 2631-4:2001 Table A.1
WEIGHTINGS = {
    "Wb": Weighting(
        name="Wb",
        f1=0.4,
        f2=100.0,
        f3=16.0,
        f4=16.0,
        q4=0.55,
        f5=2.5,
        q5=0.9,
        f6=4.0,
        q6=0.95,
        k=1.024,
        use="vertical (z) comfort, rail vehicles (ISO 2631-4, BS 6841)",
    ),
    "Wc": Weighting(
        name="Wc",
        f1=0.4,
        f2=100.0,
        f3=8.0,
        f4=8.0,
        q4=0.63,
        f5=_INF,
        q5=1.0,
        f6=_INF,
        q6=1.0,
        k=1.0,
        use="seat-back x (ISO 2631-1)",
    ),
    "Wd": Weighting(
        name="Wd",
        f1=0.4,
        f2=100.0,
        f3=2.0,
        f4=2.0,
        q4=0.63,
        f5=_INF,
        q5=1.0,
        f6=_INF,
        q6=1.0,
        k=1.0,
        use="horizontal x, y, seated, standing, recumbent (ISO 2631-1)",
    ),
    "We": Weighting(
        name="We",
        f1=0.4,
        f2=100.0,
        f3=1.0,
        f4=1.0,
        q4=0.63,
        f5=_INF,
        q5=1.0,
        f6=_INF,
        q6=1.0,
        k=1.0,
        use="rotational vibration [rad/s^2] (ISO 2631-1)",
    ),
    "Wf": Weighting(
        name="Wf",
        f1=0.08,
        f2=0.63,
        f3=_INF,
        f4=0.25,
        q4=0.86,
        f5=0.0625,
        q5=0.80,
        f6=0.10,
        q6=0.80,
        k=1.0,
        use="vertical, motion sickness, 0.1-0.5 Hz (ISO 2631-1)",
    ),
    "Wj": Weighting(
        name="Wj",
        f1=0.4,
        f2=100.0,
        f3=_INF,
        f4=_INF,
        q4=1.0,
        f5=3.75,
        q5=0.91,
        f6=5.32,
        q6=0.91,
        k=1.0,
        use="vertical, recumbent, under the head (ISO 2631-1)",
    ),
    "Wk": Weighting(
        name="Wk",
        f1=0.4,
        f2=100.0,
        f3=12.5,
        f4=12.5,
        q4=0.63,
        f5=2.37,
        q5=0.91,
        f6=3.35,
        q6=0.91,
        k=1.0,
        use="vertical z, seated, standing, recumbent (ISO 2631-1); escalator/lift ride z",
    ),
}


def get_weighting(weighting) -> Weighting:
    """A :class:`Weighting` from its name (case-insensitive: ``"Wk"``, ``"wd"`` ...) or itself."""
    if isinstance(weighting, Weighting):
        return weighting
    if isinstance(weighting, str):
        for key, w in WEIGHTINGS.items():
            if key.lower() == weighting.strip().lower():
                return w
    raise ValueError(f"Parameter weighting={weighting!r} must be one of {', '.join(WEIGHTINGS)} (or a Weighting).")


def frequency_weighting_response(f, weighting) -> np.ndarray:
    """Analytic complex frequency response ``W(j 2 pi f)`` of a weighting.

    Parameters
    ----------
    f : array_like
        Frequencies. [Hz]
    weighting : str or Weighting
        ``"Wb"``, ``"Wc"``, ``"Wd"``, ``"We"``, ``"Wf"``, ``"Wj"`` or ``"Wk"``.

    Returns
    -------
    numpy.ndarray of complex
        The weighting factor (dimensionless); ``np.abs`` gives the magnitude, ``20 log10`` of it
        the gain in dB, ``np.angle`` the phase of the analogue (causal) weighting. [-]

    Notes
    -----
    ``W = K Hh Hl Ht Hs`` (module docstring).  Examples: Wk at 1, 4, 8, 16 Hz: 0.482, 0.967,
    1.036, 0.768 (ISO 2631-1 Table 3).

    Examples
    --------
    >>> round(float(abs(frequency_weighting_response(4.0, "Wk"))), 3)
    0.967
    """
    w = get_weighting(weighting)
    f = np.asarray(f, dtype=np.float64)
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise ValueError("Parameter f must hold finite frequencies >= 0 [Hz].")
    s = 2j * np.pi * f
    h = np.full(f.shape, w.k, dtype=np.complex128)
    for b, a, _ in w.analog_sections():
        h = h * np.polyval(b, s) / np.polyval(a, s)
    return h


def frequency_weighting_sos(weighting, fs) -> np.ndarray:
    """Second-order sections of a weighting at the sample rate ``fs`` (no oversampling).

    Parameters
    ----------
    weighting : str or Weighting
    fs : float
        Sample rate the sections run at. [Hz]

    Returns
    -------
    numpy.ndarray, shape (n_sections, 6)
        For :func:`scipy.signal.sosfilt`; the gain ``K`` is in the first section.

    Notes
    -----
    Bilinear transform of each analogue section, pre-warped at its characteristic frequency.
    At ``fs >= 2000 Hz`` the magnitude is within 0.031 dB of the analytic one from 0.5 to 80 Hz
    (Wf down to -120 dB); at lower rates the error grows towards Nyquist (at 200 Hz it is
    several dB at 80 Hz): use :func:`frequency_weighting`, which oversamples, for records sampled
    slower.  A section whose pre-warping frequency is above 0.45 ``fs`` (the 100 Hz low-pass at
    ``fs < 222 Hz``) is transformed without pre-warping.
    """
    return _sos(get_weighting(weighting), check_fs(fs)).copy()


@functools.lru_cache(maxsize=64)
def _sos(w: Weighting, fs: float) -> np.ndarray:
    sections = []
    for b, a, fp in w.analog_sections():
        if fp < 0.45 * fs:
            wp = 2.0 * math.pi * fp
            c = wp / math.tan(wp / (2.0 * fs))  # s = c (1 - 1/z) / (1 + 1/z), exact at fp
        else:
            c = 2.0 * fs
        bz, az = _biquad_bilinear(b, c), _biquad_bilinear(a, c)
        sections.append(np.concatenate([bz / az[0], az / az[0]]))
    sos = np.array(sections)
    sos[0, :3] *= w.k
    return sos


def _biquad_bilinear(p, c):
    """Coefficients in 1/z of ``p2 s^2 + p1 s + p0`` (``p`` highest power first, up to degree 2)
    times ``(1 + 1/z)^2`` with ``s = c (1 - 1/z)/(1 + 1/z)``."""
    p2, p1, p0 = [0.0] * (3 - len(p)) + [float(v) for v in p]
    c2 = c * c
    return np.array([p2 * c2 + p1 * c + p0, 2.0 * (p0 - p2 * c2), p2 * c2 - p1 * c + p0])


@functools.lru_cache(maxsize=16)
def _interp_fir(factor: int) -> np.ndarray:
    """Zero-phase interpolation FIR for :func:`scipy.signal.resample_poly` (gain ``factor``)."""
    half = 24 * factor
    h = scipy.signal.firwin(2 * half + 1, 0.93 / factor, window=("kaiser", 9.0))
    return h  # resample_poly multiplies by the factor itself


def oversampling_factor(fs) -> int:
    """Integer ``L`` with ``L fs >= INTERNAL_RATE_HZ`` (1 at and above it)."""
    fs = check_fs(fs)
    return max(1, int(math.ceil(INTERNAL_RATE_HZ / fs - 1e-9)))


def frequency_weighting(x, fs, weighting, *, axis=-1, nan_policy="raise"):
    """Filter a record with a frequency weighting of ISO 2631-1 / ISO 8041.

    Parameters
    ----------
    x : array_like
        Acceleration (or, for We, angular acceleration) samples. [any unit]
    fs : float
        Sample rate. [Hz]
    weighting : str or Weighting
        ``"Wk"`` (vertical), ``"Wd"`` (horizontal), ``"Wb"``, ``"Wc"``, ``"We"``, ``"Wf"``, ``"Wj"``.
    axis : int
        Time axis.
    nan_policy : {"raise", "interpolate"}

    Returns
    -------
    numpy.ndarray
        The weighted signal, same shape and unit as ``x``.  Causal (as a meter's): its phase is
        the analogue weighting's; the filter starts from rest, so the first seconds carry the
        0.4 Hz high-pass's settling from the record's offset (remove the mean, or discard them).

    Raises
    ------
    ValueError
        Unknown weighting, bad ``fs``, or ``x`` empty, non-numeric, infinite or (by default) with NaN.

    Notes
    -----
    At ``fs < 2000 Hz`` the record is oversampled by ``L = ceil(2000 / fs)`` with a zero-phase
    Kaiser FIR (cut-off 0.93 of the original Nyquist), filtered with
    :func:`frequency_weighting_sos` at ``L fs`` and decimated by ``L``; the magnitude then matches
    :func:`frequency_weighting_response` within 0.1 dB up to 0.8 of Nyquist at any rate
    (module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> fs = 500.0; t = np.arange(0, 20, 1 / fs)
    >>> y = frequency_weighting(np.sin(2 * np.pi * 4 * t), fs, "Wk")
    >>> round(float(np.sqrt(2) * np.std(y[5000:])), 3)  # Wk at 4 Hz
    0.967
    """
    fs = check_fs(fs)
    w = get_weighting(weighting)
    x = as_signal(x, axis=axis, min_samples=2)
    x = fill_nan(x, nan_policy=nan_policy, axis=axis)
    factor = oversampling_factor(fs)
    sos = frequency_weighting_sos(w, fs * factor)
    if factor == 1:
        return scipy.signal.sosfilt(sos, x, axis=axis)
    up = scipy.signal.resample_poly(x, factor, 1, axis=axis, window=_interp_fir(factor), padtype="line")
    y = scipy.signal.sosfilt(sos, up, axis=axis)
    return np.ascontiguousarray(np.take(y, np.arange(0, y.shape[axis], factor), axis=axis))
