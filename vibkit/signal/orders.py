"""Order tracking: reference phase (tachometer, shaft angle or tracked), constant-angle resampling,
order spectra and maps, and the Vold-Kalman order filter.

Order 1 is one cycle of the reference phase.  With the link-pass phase as reference, order 1 is the
link-pass frequency; with the sprocket shaft angle, pass ``order_of_reference=1`` to
:func:`order_spectrum` and find the link-pass at order ``Z``, or multiply the shaft angle by ``Z``
(:func:`phase_from_shaft_angle`) to put it at order 1.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.interpolate
import scipy.linalg
import scipy.signal
import scipy.sparse
import scipy.sparse.linalg

from ._checks import as_signal, check_fs, check_positive_int, decimate_for_band, fill_nan, filter_with_zi, sosfiltfilt
from .estimate import expj
from .peaks import find_fundamental
from .spectral import amplitude_spectrum, spectrogram

__all__ = [
    "phase_from_tacho",
    "phase_from_shaft_angle",
    "track_phase",
    "PhaseTrack",
    "resample_to_angle",
    "AngleSignal",
    "order_spectrum",
    "order_map",
    "vold_kalman",
    "VoldKalmanResult",
    "vk_bandwidth_to_r",
    "vk_min_bandwidth",
    "VK_MAX_CONDITION",
]


def phase_from_tacho(pulse_times, t, *, pulses_per_cycle=1):
    """Reference phase at times ``t`` from tachometer pulse times.

    Parameters
    ----------
    pulse_times : array_like
        Strictly increasing pulse times, at least 3. [s]
    t : array_like
        Times at which the phase is wanted. [s]
    pulses_per_cycle : int, optional
        Pulses per reference cycle (e.g. teeth of a tone wheel).

    Returns
    -------
    ndarray
        Phase, ``2 pi`` per cycle, zero at the first pulse. [rad]

    Notes
    -----
    The cumulative cycle count ``j / pulses_per_cycle`` at pulse ``j`` is interpolated with a
    monotone cubic (PCHIP), extrapolated at the ends.
    """
    p = as_signal(pulse_times, "pulse_times", min_samples=3)
    if p.ndim != 1 or np.isnan(p).any() or np.any(np.diff(p) <= 0):
        raise ValueError("Parameter pulse_times must be a 1-D, strictly increasing array of times [s] without NaN.")
    ppc = check_positive_int(pulses_per_cycle, "pulses_per_cycle")
    cycles = np.arange(p.size) / ppc
    interp = scipy.interpolate.PchipInterpolator(p, cycles, extrapolate=True)
    return 2.0 * np.pi * interp(np.asarray(t, dtype=float))


def phase_from_shaft_angle(theta, *, teeth):
    """Link-pass phase from the sprocket shaft angle: ``Z |theta|`` (one link per tooth). [rad]"""
    z = check_positive_int(teeth, "teeth")
    theta = as_signal(theta, "theta")
    return z * np.abs(theta)


@dataclass(frozen=True)
class PhaseTrack:
    """Result of :func:`track_phase`.

    Attributes
    ----------
    phase_rad : ndarray
        Reference (order-1) phase at every sample. [rad]
    frequency_hz : ndarray
        Instantaneous reference frequency at every sample. [Hz]
    ridge_time_s, ridge_hz : ndarray
        The coarse spectrogram ridge (frame centres, fundamental). [s], [Hz]
    harmonics_used : tuple of int
    """

    phase_rad: np.ndarray
    frequency_hz: np.ndarray
    ridge_time_s: np.ndarray
    ridge_hz: np.ndarray
    harmonics_used: tuple


#: values (frequency rows x frames, or samples) :func:`track_phase` computes at a time in its block loops: 2 M
#: values are 16 MB as floats, 32 MB complex, whatever the record's length
SPECTROGRAM_BLOCK_VALUES = 1 << 21


@functools.lru_cache(maxsize=64)
def _butter_low(order, cutoff, fs):
    """The Butterworth low-pass's second-order sections and their initial conditions (read-only,
    :func:`vibkit.signal._checks.filter_with_zi`): designed once per order, cutoff and rate, where a record's
    harmonics and every record of a fleet ask for the same few (the design cost as much as the filtering of a 30 s
    record)."""
    return filter_with_zi(scipy.signal.butter(order, cutoff, btype="low", fs=fs, output="sos"))


def _lowpass(y, fs, cutoff, order=4, padtype="even"):
    # Even (mirror) extension over three time constants: no start-up transient, and unlike the
    # default odd extension it does not hinge on the (noisy) end samples.
    padlen = min(y.size - 1, int(3.0 * fs / cutoff))
    return sosfiltfilt(_butter_low(int(order), float(cutoff), float(fs)), y, padtype=padtype, padlen=padlen)


def track_phase(x, fs, *, band, n_harmonics=3, frame_s=None, bandwidth_hz=None, max_deviation=0.1, nan_policy="raise"):
    """Instantaneous link-pass phase and frequency without a tachometer.

    Parameters
    ----------
    x : array_like, 1-D
        Signal with a link-pass harmonic family. [x]
    fs : float
        Sampling frequency. [Hz]
    band : (float, float)
        Plausible range of the mean fundamental. [Hz]
    n_harmonics : int, optional
        Harmonics combined in the phase estimate.
    frame_s : float, optional
        Spectrogram frame for the coarse ridge; default 8 periods of the fundamental. [s]
    bandwidth_hz : float, optional
        Bandwidth of the frequency track (how fast speed may change); default ``f0 / 20``. [Hz]
    max_deviation : float, optional
        Largest relative departure of the instantaneous from the mean fundamental.
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    PhaseTrack

    Notes
    -----
    1. Ridge: per frame, the peak of the strongest harmonic ``h*`` within
       ``h* f0 (1 +- max_deviation)``, parabolically interpolated; integrated into a coarse phase.
    2. Phase: each harmonic ``h`` is demodulated by ``exp(-j h phi_ridge)``, low-passed at
       ``bandwidth_hz``; its residual phase over ``h`` corrects the coarse phase.  Harmonics are
       combined with weights ``h**2 |a_h|**2`` (inverse phase-noise variance).
    3. Frequency: derivative of the combined phase, low-passed at ``bandwidth_hz``.

    The first and last ``1 / bandwidth_hz`` seconds carry filter end effects.

    References
    ----------
    H. Vold, J. Leuridan, SAE Technical Paper 931288 (1993); K. R. Fyfe, E. D. S. Munck,
    Mech. Syst. Signal Process. 11 (1997) 187-205.
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=16)
    if x.ndim != 1:
        raise ValueError(f"Parameter x must be 1-D, got shape {x.shape}.")
    x = fill_nan(x, nan_policy=nan_policy)
    kmax = check_positive_int(n_harmonics, "n_harmonics")
    if not 0.0 < float(max_deviation) < 0.5:
        raise ValueError(f"Parameter max_deviation={max_deviation!r} must lie in (0, 0.5).")
    fund = find_fundamental(x, fs, band=band)
    f0 = fund.frequency_hz
    kmax = max(1, min(kmax, int((0.45 * fs) // (f0 * (1 + max_deviation)))))
    # Track on a decimated copy (only the harmonics matter), return at the original rate.
    fs_full, n_full = fs, x.size
    x, fs, q = decimate_for_band(x, fs, (kmax + 1) * f0 * (1 + max_deviation), oversample=6.0)
    h_star = int(np.argmax(fund.harmonic_snr_db[:kmax])) + 1
    if frame_s is None:
        frame_s = 8.0 / f0
    nper = int(round(float(frame_s) * fs))
    n = x.size
    if nper < 8 or nper > n:
        raise ValueError(
            f"Parameter frame_s={frame_s!r} gives {nper} samples per frame; expected 8..{n} for this record."
        )
    if bandwidth_hz is None:
        bandwidth_hz = f0 / 20.0
    bw = float(bandwidth_hz)
    if not 0.0 < bw < f0 / 2.0:
        raise ValueError(f"Parameter bandwidth_hz={bandwidth_hz!r} must lie in (0, f0/2 = {f0 / 2:g}) Hz.")
    # 1. coarse ridge of harmonic h*
    hop = max(1, nper // 4)
    nfft = 1 << int(np.ceil(np.log2(8 * nper)))
    # scipy.signal.spectrogram's frames, a block of frames at a time, keeping only the band's rows: the whole
    # spectrogram of a day-long record (all nfft / 2 + 1 rows, complex on the way) took gigabytes; a frame's
    # values do not depend on its neighbours, and the frequencies and times are scipy's formulas
    f = scipy.fft.rfftfreq(nfft, 1 / fs)
    tf = np.arange(nper / 2, n - nper / 2 + 1, hop) / float(fs)
    lo, hi = h_star * f0 * (1 - max_deviation), h_star * f0 * (1 + max_deviation)
    sel = np.flatnonzero((f >= lo) & (f <= hi))
    if sel.size < 3:
        raise ValueError(f"Parameter frame_s={frame_s!r} is too short to resolve the band {lo:.4g}-{hi:.4g} Hz.")
    xc = x - x.mean()
    n_frames = (n - (nper - hop)) // hop
    per_block = max(1, SPECTROGRAM_BLOCK_VALUES // nfft)
    sub = np.empty((sel.size, n_frames))
    for j0 in range(0, n_frames, per_block):
        j1 = min(n_frames, j0 + per_block)
        _f, _t, s = scipy.signal.spectrogram(
            xc[j0 * hop : (j1 - 1) * hop + nper],
            fs,
            window="hann",
            nperseg=nper,
            noverlap=nper - hop,
            nfft=nfft,
            mode="magnitude",
        )
        sub[:, j0:j1] = s[sel]
    del xc  # each record-length temporary freed once used (a day at 200 Hz: 23 MB each after decimation)
    i = np.argmax(sub, axis=0)
    i = np.clip(i, 1, sel.size - 2)
    cols = np.arange(sub.shape[1])
    a, b, c = np.log(sub[i - 1, cols] + 1e-300), np.log(sub[i, cols] + 1e-300), np.log(sub[i + 1, cols] + 1e-300)
    den = a - 2 * b + c
    delta = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, 1.0), 0.0)
    ridge = (f[sel][i] + delta * (f[1] - f[0])) / h_star
    t = np.arange(n) / fs
    if tf.size >= 2:
        f_r = np.interp(t, tf, ridge)
        f_r = _lowpass(f_r, fs, min(bw, 0.4 / (hop / fs) / 2), order=2) if n > 30 else f_r
    else:
        f_r = np.full(n, ridge[0])
    phi_r = 2.0 * np.pi * np.concatenate(([0.0], np.cumsum((f_r[1:] + f_r[:-1]) / 2.0) / fs))
    del f_r
    # 2. demodulate each harmonic around the coarse phase
    acc = np.zeros(n)
    wsum = 0.0
    offset1 = 0.0
    used = []
    for h in range(1, kmax + 1):
        # x exp(-j h phi_r), in place: one complex array of the record's length, not three
        z = expj((-1j * h).imag * phi_r)
        z *= x
        zr = _lowpass(z.real, fs, bw)
        zi = _lowpass(z.imag, fs, bw)
        del z
        psi = np.unwrap(np.arctan2(zi, zr))
        amp2 = float(np.mean(zr * zr + zi * zi))
        w = h * h * amp2
        dev = (psi - psi.mean()) / h
        acc += w * dev
        wsum += w
        used.append(h)
        if h == 1:
            offset1 = float(psi.mean())
        del zr, zi, psi, dev
    phase = phi_r + acc / wsum + offset1
    del acc, phi_r, x
    # 3. frequency from the phase derivative
    freq = np.gradient(phase, 1.0 / fs) / (2.0 * np.pi)
    freq = _lowpass(freq, fs, bw, padtype="odd")  # the phase is smooth: odd extension keeps the end slope
    if q > 1:  # back at the record's rate, a block of samples at a time
        phase, freq = _spline_blocks(t, phase, fs_full, n_full), _interp_blocks(t, freq, fs_full, n_full)
    return PhaseTrack(phase, freq, tf, ridge, tuple(used))


#: knots of the decimated phase each side of a block beyond the samples it gives (:func:`_spline_blocks`): a cubic
#: spline's value moves with a knot's end condition by (2 - sqrt 3)^k = 0.27^k at k knots from it, 1e-36 at 64
SPLINE_OVERLAP_KNOTS = 64


def _spline_blocks(t, y, fs_full, n_full, block=None):
    """``CubicSpline(t, y)`` (not-a-knot) at ``arange(n_full) / fs_full``, a block of ``block`` output samples at a
    time, each from the spline of the knots under it and :data:`SPLINE_OVERLAP_KNOTS` more on each side: equal to
    the record-length spline within rounding (its end conditions are the record's at the record's ends, and reach
    a block's samples from 64 knots away elsewhere), in memory a block's knots instead of the record's (``block``:
    default :data:`SPECTROGRAM_BLOCK_VALUES`)."""
    block = block or SPECTROGRAM_BLOCK_VALUES
    out = np.empty(n_full)
    for i0 in range(0, n_full, block):
        t_out = np.arange(i0, min(n_full, i0 + block)) / fs_full
        j0 = max(0, int(np.searchsorted(t, t_out[0], side="right")) - 1 - SPLINE_OVERLAP_KNOTS)
        j1 = min(t.size, int(np.searchsorted(t, t_out[-1], side="left")) + 1 + SPLINE_OVERLAP_KNOTS)
        out[i0 : i0 + t_out.size] = scipy.interpolate.CubicSpline(t[j0:j1], y[j0:j1])(t_out)
    return out


def _interp_blocks(t, y, fs_full, n_full, block=None):
    """``np.interp(arange(n_full) / fs_full, t, y)``, a block of output samples at a time (the same values)."""
    block = block or SPECTROGRAM_BLOCK_VALUES
    out = np.empty(n_full)
    for i0 in range(0, n_full, block):
        t_out = np.arange(i0, min(n_full, i0 + block)) / fs_full
        out[i0 : i0 + t_out.size] = np.interp(t_out, t, y)
    return out


@dataclass(frozen=True)
class AngleSignal:
    """A signal resampled at constant reference angle.

    Attributes
    ----------
    cycles : ndarray
        Uniform grid of reference cycles (revolutions of the reference phase).
    x : ndarray
        Signal at those angles. [x]
    time_s : ndarray
        Time of each angle sample. [s]
    samples_per_cycle : int
    """

    cycles: np.ndarray
    x: np.ndarray
    time_s: np.ndarray
    samples_per_cycle: int


def resample_to_angle(x, fs, phase, *, samples_per_cycle=32, antialias=True, nan_policy="raise"):
    """Computed order tracking: resample ``x`` to constant increments of the reference phase.

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    phase : array_like, 1-D
        Reference phase at every sample, increasing (tachometer, shaft angle or
        :func:`track_phase`). [rad]
    samples_per_cycle : int, optional
        Angle samples per reference cycle; orders up to ``samples_per_cycle / 2`` are kept.
    antialias : bool, optional
        Low-pass at ``0.4 samples_per_cycle f_min`` before resampling when that is below
        ``0.4 fs``, with ``f_min`` the slowest reference frequency (the signal is first
        decimated to about four times that frequency, which keeps the spline cheap).
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    AngleSignal
        Whole cycles only, from the first to the last complete one.

    Notes
    -----
    Times of the target angles come from linear interpolation of ``t(phase)``; the signal is
    evaluated there with a cubic spline in time.
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=4)
    x = fill_nan(x, nan_policy=nan_policy)
    ph = as_signal(phase, "phase", min_samples=4)
    if x.ndim != 1 or ph.shape != x.shape:
        raise ValueError(f"Parameters x and phase must be 1-D of equal length, got {x.shape} and {ph.shape}.")
    if np.isnan(ph).any() or np.any(np.diff(ph) <= 0):
        raise ValueError(
            "Parameter phase must increase strictly at every sample (no NaN); reverse the sign of a decreasing angle."
        )
    spc = check_positive_int(samples_per_cycle, "samples_per_cycle", minimum=4)
    t = np.arange(x.size) / fs
    t_full = t
    c = ph / (2.0 * np.pi)
    if antialias:
        f_min = float(np.min(np.diff(c))) * fs
        cutoff = 0.4 * spc * f_min
        if cutoff < 0.4 * fs:
            # decimate first (cheap spline), then cut at the angle-domain Nyquist
            x, fs_d, q = decimate_for_band(x, fs, cutoff, oversample=4.0)
            t = t[::q]
            x = _lowpass(x, fs_d, cutoff, order=8)
    start, stop = np.ceil(c[0]), np.floor(c[-1])
    if stop - start < 1:
        raise ValueError("Parameter phase covers less than one complete reference cycle; expected at least one.")
    grid = start + np.arange(int((stop - start) * spc)) / spc
    tg = np.interp(grid, c, t_full)
    spline = scipy.interpolate.CubicSpline(t, x)
    return AngleSignal(grid, spline(tg), tg, spc)


def order_spectrum(angle_signal, *, window="hann", order_of_reference=1.0):
    """Amplitude spectrum over orders of an :class:`AngleSignal`.

    Parameters
    ----------
    angle_signal : AngleSignal
    window : str, optional
        As :func:`vibkit.signal.amplitude_spectrum`.
    order_of_reference : float, optional
        Order of one reference cycle (1 for the link-pass phase; 1 for a shaft whose link-pass
        shows at order ``Z``).

    Returns
    -------
    orders : ndarray
    amplitude : ndarray
        Peak amplitude per order bin. [x]
    """
    if not isinstance(angle_signal, AngleSignal):
        raise ValueError("Parameter angle_signal must be an AngleSignal (from resample_to_angle).")
    o, a = amplitude_spectrum(angle_signal.x, angle_signal.samples_per_cycle, window=window)
    return o * float(order_of_reference), a


def order_map(x, fs, phase, *, samples_per_cycle=32, cycles_per_frame=16, overlap=0.5):
    """Order spectra over time (an order map).

    Parameters
    ----------
    x, fs, phase, samples_per_cycle :
        As :func:`resample_to_angle`.
    cycles_per_frame : int, optional
        Reference cycles per frame (order resolution ``1 / cycles_per_frame``).
    overlap : float, optional
        Frame overlap fraction in [0, 1).

    Returns
    -------
    orders : ndarray
    time_s : ndarray
        Time of each frame centre. [s]
    amplitude : ndarray
        Peak amplitude, orders by frames. [x]
    """
    ang = resample_to_angle(x, fs, phase, samples_per_cycle=samples_per_cycle)
    cpf = check_positive_int(cycles_per_frame, "cycles_per_frame")
    if not 0.0 <= float(overlap) < 1.0:
        raise ValueError(f"Parameter overlap={overlap!r} must lie in [0, 1).")
    nper = cpf * ang.samples_per_cycle
    if nper > ang.x.size:
        raise ValueError(
            f"Parameter cycles_per_frame={cpf} is longer than the record ({ang.x.size // ang.samples_per_cycle} cycles)."
        )
    nover = int(round(float(overlap) * nper))
    o, cc, s = spectrogram(ang.x, ang.samples_per_cycle, nperseg=nper, noverlap=nover)
    centre_cycles = ang.cycles[0] + cc
    return o, np.interp(centre_cycles, ang.cycles, ang.time_s), s


#: the largest condition number ``16 r**2`` of the Vold-Kalman system that :func:`vold_kalman` solves
VK_MAX_CONDITION = 1e12


def vk_min_bandwidth(fs) -> float:
    """The narrowest ``bandwidth_hz`` of :func:`vold_kalman` at sampling frequency ``fs`` [Hz]: the band
    whose system has the condition number :data:`VK_MAX_CONDITION` (about ``3.2e-4 fs``). [Hz]"""
    r_max = np.sqrt(VK_MAX_CONDITION / 16.0)
    return float(fs / np.pi * np.arcsin(np.sqrt(1.0 / (4.0 * r_max))))


def vk_bandwidth_to_r(bandwidth_hz, fs):
    """Weighting ``r`` of a second-order Vold-Kalman filter with -3 dB half-bandwidth ``bandwidth_hz``.

    Notes
    -----
    The filter's response is ``1 / (1 + r**2 (2 sin(w/2))**4)``; half power at
    ``w = 2 pi bandwidth_hz / fs`` gives ``r = 1 / (4 sin(pi bandwidth_hz / fs)**2)``.
    """
    return 1.0 / (4.0 * np.sin(np.pi * bandwidth_hz / fs) ** 2)


def _vk_banded(n, r2):
    ab = np.zeros((3, n))
    diag = np.full(n, 6.0)
    diag[[0, -1]] = 1.0
    if n > 2:
        diag[[1, -2]] = 5.0
    sup1 = np.full(n - 1, -4.0)
    sup1[[0, -1]] = -2.0
    ab[2] = 1.0 + r2 * diag
    ab[1, 1:] = r2 * sup1
    ab[0, 2:] = r2
    return ab


def _vk_sparse(n, r2):
    d = scipy.sparse.diags([np.ones(n - 2), -2.0 * np.ones(n - 2), np.ones(n - 2)], [0, 1, 2], shape=(n - 2, n))
    return (scipy.sparse.identity(n) + r2 * (d.T @ d)).tocsc()


@dataclass(frozen=True)
class VoldKalmanResult:
    """Result of :func:`vold_kalman`.

    Attributes
    ----------
    waveform : ndarray
        The extracted order's waveform ``2 Re(a e^{j theta})``. [x]
    envelope : ndarray, complex
        Complex envelope ``a``; peak amplitude ``2 |a|``. [x]
    amplitude : ndarray
        ``2 |a|``. [x]
    r : float
        Weighting used.
    """

    waveform: np.ndarray
    envelope: np.ndarray
    amplitude: np.ndarray
    r: float


def vold_kalman(x, fs, phase, *, order=1.0, bandwidth_hz, solver="pentadiagonal", nan_policy="raise"):
    """Second-generation Vold-Kalman filter: extract one order's waveform.

    Parameters
    ----------
    x : array_like, 1-D
        Signal. [x]
    fs : float
        Sampling frequency. [Hz]
    phase : array_like, 1-D
        Reference phase at every sample. [rad]
    order : float, optional
        Order to extract (multiple of the reference phase).
    bandwidth_hz : float
        -3 dB half-bandwidth around the order. [Hz]
    solver : {"pentadiagonal", "banded", "sparse"}, optional
        ``"pentadiagonal"`` (default): O(n) LDL^T written for this matrix (numba);
        ``"banded"``: :func:`scipy.linalg.solveh_banded`; ``"sparse"``:
        :func:`scipy.sparse.linalg.spsolve` of the same system (reference).
    nan_policy : {"raise", "interpolate"}, optional

    Returns
    -------
    VoldKalmanResult

    Raises
    ------
    ValueError
        ``bandwidth_hz`` outside ``(0, fs/4)`` or narrower than :func:`vk_min_bandwidth` (the
        system's condition number over :data:`VK_MAX_CONDITION`); the message names the parameter
        and the limit.

    Notes
    -----
    Minimises ``sum |x e^{-j theta} - a|**2 + r**2 sum |a[n] - 2 a[n+1] + a[n+2]|**2`` with
    ``theta = order * phase``: ``(I + r**2 D^T D) a = x e^{-j theta}``.  ``r`` from
    :func:`vk_bandwidth_to_r`.  Very narrow bands at high ``fs`` make the system ill-conditioned
    (condition about ``16 r**2``): a band whose condition exceeds ``16 r**2 = 1e12``
    (:data:`VK_MAX_CONDITION`; ``bandwidth_hz`` below :func:`vk_min_bandwidth`, about ``3.2e-4 fs``)
    is refused; decimate first.

    References
    ----------
    H. Vold, M. Mains, J. Blough, SAE Technical Paper 972007 (1997).
    J. Tuma, Proc. 6th Int. Carpathian Control Conf. (2005).
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=8)
    x = fill_nan(x, nan_policy=nan_policy)
    ph = as_signal(phase, "phase", min_samples=8)
    if x.ndim != 1 or ph.shape != x.shape:
        raise ValueError(f"Parameters x and phase must be 1-D of equal length, got {x.shape} and {ph.shape}.")
    try:
        bw = float(bandwidth_hz)
    except (TypeError, ValueError):
        raise ValueError(f"Parameter bandwidth_hz={bandwidth_hz!r} must be a positive frequency [Hz].") from None
    if not 0.0 < bw < fs / 4.0:
        raise ValueError(f"Parameter bandwidth_hz={bandwidth_hz!r} must lie in (0, fs/4 = {fs / 4:g}) Hz.")
    if solver not in ("pentadiagonal", "banded", "sparse"):
        raise ValueError(f"Parameter solver={solver!r} must be 'pentadiagonal', 'banded' or 'sparse'.")
    r = vk_bandwidth_to_r(bw, fs)
    r2 = r * r
    if 16.0 * r2 > VK_MAX_CONDITION:
        raise ValueError(
            f"Parameter bandwidth_hz={bw:g} is too narrow for fs={fs:g} Hz: the filter's condition number "
            f"16 r**2 = {16 * r2:.1e} exceeds the limit {VK_MAX_CONDITION:.0e} (amplitudes lose accuracy); "
            f"give bandwidth_hz >= {vk_min_bandwidth(fs):.4g} Hz or decimate the signal first."
        )
    theta = float(order) * ph
    y = x * np.exp(-1j * theta)
    n = x.size
    if solver == "pentadiagonal":
        from .kernels import _vk_solve  # numba on the first use, not with the package

        a = _vk_solve(y, r2)
    else:
        rhs = np.column_stack([y.real, y.imag])
        if solver == "banded":
            sol = scipy.linalg.solveh_banded(_vk_banded(n, r2), rhs, check_finite=False)
        else:
            sol = scipy.sparse.linalg.spsolve(_vk_sparse(n, r2), rhs)
        a = sol[:, 0] + 1j * sol[:, 1]
    return VoldKalmanResult(2.0 * np.real(a * np.exp(1j * theta)), a, 2.0 * np.abs(a), float(r))
