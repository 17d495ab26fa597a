"""The link map: every link-pass cycle of a recording given the number of its link, per-link features
averaged over the chain's loops.

A chain of ``N`` links passes the sensor once per loop, ``N / f_lp`` seconds.  With the link-pass
phase ``phi`` (tracked or from a shaft angle), cycle ``j`` is ``2 pi j <= phi' < 2 pi (j + 1)``, where
``phi'`` is ``phi`` shifted so that the signal's fundamental peaks at ``phi' = 0`` (the same cycle
boundaries whatever the phase's origin).  The link of cycle ``j`` is ``(j - j_ref) mod N`` (0 for
link 1), ``j_ref`` the cycle in progress at the start of the recording or at a marker time.

Per cycle, three features: the waveform resampled at ``samples_per_cycle`` points of the phase, minus
the record's mean cycle and without its component along the mean cycle's slope (the *shape*: what a
small phase error at that cycle cannot explain), its mean level, and the cycle's duration.  Averaged per link over ``L``
complete loops, with their loop-to-loop scatter: :class:`LinkMap`.

The decision, with a stated false-alarm probability: :mod:`vibkit.signal.linkscan`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._checks import as_signal, check_fs, check_positive_int
from .orders import _lowpass as _orders_lowpass
from .orders import resample_to_angle

__all__ = [
    "LinkMap",
    "TooFewLoops",
    "canonical_phase",
    "link_map",
    "smooth_phase",
    "link_pass_phase",
    "record_time_for_loops",
]

#: loops a decision needs at least (the scatter comes from loop-to-loop differences)
MIN_LOOPS = 2


class TooFewLoops(ValueError):
    """The recording covers fewer than two complete loops of the chain; the message says how long to record."""


def record_time_for_loops(n_links, link_pass_hz, loops=MIN_LOOPS):
    """Recording time that covers ``loops`` loops of ``n_links`` links, plus one link cycle. [s]"""
    return (loops * n_links + 1) / float(link_pass_hz)


def canonical_phase(x, phase):
    """``phase`` shifted so that the fundamental of ``x`` (one cycle of ``phase``) peaks at 0. [rad]"""
    x = np.asarray(x, dtype=float)
    a = float(np.mean((x - x.mean()) * np.cos(phase)))
    b = float(np.mean((x - x.mean()) * np.sin(phase)))
    return phase - math.atan2(b, a)


@dataclass(frozen=True)
class LinkMap:
    """Result of :func:`link_map`: per-link features over ``loops`` complete loops.

    Attributes
    ----------
    n_links, loops, samples_per_cycle : int
    link_pass_hz : float
        Mean link-pass frequency over the loops used. [Hz]
    first_link : int
        0-based number of the first complete cycle's link (its loop starts there).
    start_s : float
        Time of the first cycle used. [s]
    shape : ndarray (loops, n_links, samples_per_cycle)
        Each cycle's waveform minus the mean cycle, by loop and link number. [x]
    duration_s : ndarray (loops, n_links)
        Each cycle's duration minus the mean cycle duration. [s]
    level : ndarray (loops, n_links)
        Each cycle's mean level minus the record's. [x]
    cycle_time_s : ndarray (loops, n_links)
        Start time of each cycle. [s]
    """

    n_links: int
    loops: int
    samples_per_cycle: int
    link_pass_hz: float
    first_link: int
    start_s: float
    shape: np.ndarray
    duration_s: np.ndarray
    level: np.ndarray
    cycle_time_s: np.ndarray

    @property
    def mean_shape(self):
        """Per-link shape averaged over the loops, ``(n_links, samples_per_cycle)``. [x]"""
        return self.shape.mean(axis=0)

    @property
    def loop_s(self):
        """Time of one loop. [s]"""
        return self.n_links / self.link_pass_hz


def link_map(x, fs, phase, n_links, *, samples_per_cycle=16, marker_s=None, link_offset=0.0):
    """Per-link features of a recording over its complete loops.

    Parameters
    ----------
    x : array_like, 1-D
        Signal with a link-pass harmonic family (finite). [x]
    fs : float
        Sampling frequency. [Hz]
    phase : array_like, 1-D
        Link-pass phase at every sample, strictly increasing (:func:`vibkit.signal.track_phase`). [rad]
    n_links : int
        Links in the chain.
    samples_per_cycle : int, optional
        Points of the phase per link cycle.
    marker_s : float, optional
        Time at which a marked link passed the sensor: it becomes link 1. Default: the link whose
        cycle is in progress at the first sample is link 1. [s]
    link_offset : float, optional
        Where the links' own boundaries (a roller at the sensor) fall in the signal's cycle, as a fraction
        of a cycle after its zero (the fundamental's peak), when the escalator's geometry says so (a scene:
        :func:`vibkit.diagnose.links.worn_link_signature`); the link in progress at the first sample (or at
        ``marker_s``) is then counted between those boundaries, not the signal's.  Default 0: the signal's
        cycles.

    Returns
    -------
    LinkMap

    Raises
    ------
    TooFewLoops
        When fewer than two complete loops are covered (the message says how long to record).
    ValueError
        On bad parameters.
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=16)
    ph = as_signal(phase, "phase", min_samples=16)
    n = check_positive_int(n_links, "n_links", minimum=2)
    spc = check_positive_int(samples_per_cycle, "samples_per_cycle", minimum=4)
    if x.ndim != 1 or ph.shape != x.shape:
        raise ValueError(f"Parameters x and phase must be 1-D of equal length, got {x.shape} and {ph.shape}.")
    t = np.arange(x.size) / fs
    ph = canonical_phase(x, ph)
    cyc = ph / (2.0 * np.pi)
    span = (x.size - 1) / fs
    f_lp = (cyc[-1] - cyc[0]) / span if span > 0 else 0.0
    if marker_s is None:
        ref = math.floor(cyc[0] - link_offset)
    else:
        m = float(marker_s)
        if not (math.isfinite(m) and 0.0 <= m <= t[-1]):
            raise ValueError(f"Parameter marker_s={marker_s!r} must lie within the recording, 0 to {t[-1]:.6g} s.")
        ref = math.floor(float(np.interp(m, t, cyc)) - link_offset)
    ang = resample_to_angle(x, fs, ph, samples_per_cycle=spc)
    n_cyc = ang.x.size // spc
    loops = n_cyc // n
    if loops < MIN_LOOPS:
        need = record_time_for_loops(n, f_lp) if f_lp > 0 else math.inf
        raise TooFewLoops(
            f"the recording covers {n_cyc / n:.2f} loops of the chain's {n} links ({span:.1f} s at "
            f"{f_lp:.4g} Hz link pass); a link map needs {MIN_LOOPS} complete loops: record at least "
            f"{math.ceil(need):.0f} s ({MIN_LOOPS} x {n} / {f_lp:.4g} Hz plus one link)"
        )
    first = int(round(ang.cycles[0]))
    used = loops * n
    wave = ang.x[: used * spc].reshape(used, spc)
    bounds = np.interp(first + np.arange(used + 1), cyc, t)
    dur = np.diff(bounds)
    # slow drift (settling, temperature, load) removed by a moving mean over one loop: a loop-periodic
    # pattern averages to a constant over any window of one loop, so it is kept
    wave = wave - _loop_mean(wave, n)
    dur = dur - _loop_mean(dur, n)
    level = wave.mean(axis=1)
    mean_cycle = wave.mean(axis=0)
    shape = wave - mean_cycle
    # a small error of the phase at one cycle shifts its waveform along the mean cycle's slope: that
    # direction is taken out of every cycle's shape (the map keeps what the phase cannot explain)
    slope = (np.roll(mean_cycle, -1) - np.roll(mean_cycle, 1)) / 2.0
    if np.any(slope):
        shape = shape - np.outer(shape @ slope / float(slope @ slope), slope)
    first_link = (first - ref) % n
    # roll so that axis 1 is the link number: cycle i of the record is link (first_link + i) mod n
    order = (first_link + np.arange(used)) % n

    def by_link(a):
        out = np.empty((loops, n) + a.shape[1:])
        lp = np.arange(used) // n
        out[lp, order] = a
        return out

    return LinkMap(
        n,
        loops,
        spc,
        float(used / (bounds[-1] - bounds[0])),
        int(first_link),
        float(bounds[0]),
        by_link(shape),
        by_link(dur - dur.mean()),
        by_link(level - level.mean()),
        by_link(bounds[:-1]),
    )


def _loop_mean(a, n):
    """Mean over the window of ``n`` cycles centred on each cycle (clipped to the record)."""
    c = np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, axis=0)])
    lo = np.clip(np.arange(a.shape[0]) - n // 2, 0, a.shape[0] - n)
    return (c[lo + n] - c[lo]) / n


def _lowpass(y, fs, cutoff, padtype="even"):
    """Zero-phase second-order low-pass: :mod:`.orders`' (its design kept per cutoff and rate; scipy's
    ``sosfiltfilt`` numbers, bit for bit)."""
    return _orders_lowpass(y, fs, float(cutoff), order=2, padtype=padtype)


def link_pass_phase(x, fs, f0, *, bandwidth_hz, n_harmonics=4):
    """Link-pass phase by demodulation at the mean frequency: ``2 pi f t + psi(t)``. [rad]

    Parameters
    ----------
    x : array_like, 1-D
        Signal with a link-pass harmonic family (finite). [x]
    fs : float
        Sampling frequency. [Hz]
    f0 : float
        Approximate mean link-pass frequency (refined here to the peak of the strongest harmonic). [Hz]
    bandwidth_hz : float
        How fast the speed may wander: each harmonic is demodulated and low-passed at it. [Hz]
    n_harmonics : int, optional

    Notes
    -----
    Each harmonic ``h`` is demodulated by ``exp(-j h 2 pi f t)`` and low-passed; its unwrapped phase
    over ``h`` is the phase's slow departure ``psi``; harmonics are combined with weights
    ``h^2 |a_h|^2``; three passes, each around the phase of the last.  The passes start from the mean
    frequency's straight line and, again, from the strongest harmonic's own phase in a band of ``+-f / 4``
    smoothed to ``bandwidth_hz``, where that band's amplitude never fades under half its median (speed steps
    faster than the bandwidth, a passenger boarding, cost the first whole cycles; noise a few times the
    fundamental, the second); the phase kept is the one under which the harmonics add up most over the
    record.  Without a spectrogram ridge the phase follows the
    chain, not the frame grid: on a chain at constant speed it stays within milliradians of the truth.
    """
    fs = check_fs(fs)
    x = as_signal(x, min_samples=16)
    x = x - x.mean()
    t = np.arange(x.size) / fs
    kmax = max(1, min(check_positive_int(n_harmonics, "n_harmonics"), int(0.45 * fs / f0)))
    amps = [abs(np.mean(x * np.exp(-2j * np.pi * h * f0 * t))) for h in range(1, kmax + 1)]
    hs = int(np.argmax(amps)) + 1
    # refine the frequency on the strongest harmonic: the peak within +-2 bins
    grid = f0 + np.linspace(-2.0, 2.0, 81) / (t[-1] * hs)
    every = max(1, x.size // 20000)
    f = float(grid[_strongest_on_grid(x[::every], t[::every], hs * grid)])
    # harmonics weaker than a tenth of the strongest add noise and unwrapping slips, not information
    used = [h for h in range(1, kmax + 1) if amps[h - 1] >= 0.1 * max(amps)]
    # the passes start from the mean frequency's straight line, and again from the strongest harmonic's own phase
    # in a band of +-f / 4 smoothed to the tracking bandwidth. A chain slowed a twentieth by a passenger boarding
    # is twice that bandwidth off the line: demodulated around it, the harmonics' phases lose whole cycles there.
    # The band's phase is a start only where it cannot slip: its amplitude nowhere under half its median (noise
    # twice the fundamental's r.m.s. in white noise at 200 Hz fades it to a third). The phase kept is the one
    # under which the harmonics add up most over the record: a phase that lost a cycle does not.
    z = x * np.exp(-2j * np.pi * hs * f * t)
    zr, zi = _lowpass(z.real, fs, 0.25 * f), _lowpass(z.imag, fs, 0.25 * f)
    line = 2.0 * np.pi * f * t
    starts = [line]
    level = np.hypot(zr, zi)
    if np.min(level) >= 0.5 * np.median(level):
        starts.append(smooth_phase(line + np.unwrap(np.arctan2(zi, zr)) / hs, fs, bandwidth_hz))
    tracked = [_refine(x, fs, start, used, bandwidth_hz) for start in starts]
    phase = max(tracked, key=lambda ph: sum(abs(np.mean(x * np.exp(-1j * h * ph))) ** 2 for h in used))
    if not np.all(np.diff(phase) > 0):
        phase = smooth_phase(phase, fs, bandwidth_hz)
    if not np.all(np.diff(phase) > 0):
        raise ValueError(
            "the link-pass phase could not be followed: it runs backwards somewhere (a dropout, or a speed "
            "that changes faster than the tracking bandwidth)"
        )
    return phase


def _strongest_on_grid(x, t, grid):
    """The index of the frequency of the evenly spaced ``grid`` [Hz] where ``|sum x exp(-2 pi j f t)|`` is largest.

    Each frequency's phasors are the last one's times one step's, ``exp(-2 pi j df t)``: two exponentials a sample
    for the whole grid instead of one a sample and frequency (81 x 20,000 for a long record)."""
    z = x * np.exp(-2j * np.pi * grid[0] * t)
    step = np.exp(-2j * np.pi * (grid[1] - grid[0]) * t)
    power = np.empty(grid.size)
    for k in range(grid.size):
        power[k] = abs(z.sum())
        z *= step
    return int(np.argmax(power))


def _refine(x, fs, phase, used, bandwidth_hz):
    """Three passes, each demodulating the harmonics ``used`` around the last phase: the filter's loss on a wander
    shrinks geometrically."""
    for _ in range(3):
        acc, wsum = np.zeros(x.size), 0.0
        for h in used:
            z = x * np.exp(-1j * h * phase)
            zr, zi = _lowpass(z.real, fs, bandwidth_hz), _lowpass(z.imag, fs, bandwidth_hz)
            psi = np.unwrap(np.arctan2(zi, zr)) / h
            w = h * h * float(np.mean(zr * zr + zi * zi))
            acc += w * (psi - psi.mean())
            wsum += w
        phase = phase + acc / wsum
    return phase


def smooth_phase(phase, fs, bandwidth_hz):
    """``phase`` with its departure from a straight line low-passed at ``bandwidth_hz``. [rad]

    A tracked phase can carry short glitches where the waveform changes; the link map needs a phase
    that increases at every sample and follows the speed's wander, not those glitches.
    """
    ph = as_signal(phase, "phase", min_samples=16)
    fs = check_fs(fs)
    t = np.arange(ph.size) / fs
    line = np.polyval(np.polyfit(t, ph, 1), t)
    return line + _lowpass(ph - line, fs, bandwidth_hz)
