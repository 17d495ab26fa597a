"""Ride-quality metrics of a step-riding (or car-riding) accelerometer: peak-to-peak values by
half-cycles, their maximum and A95, r.m.s., and the ride segment found from the record.

These are the quantities that escalator and lift ride-quality meters report (ISO 18738-1 for lifts,
ISO 18738-2 for escalators and moving walks, now the ISO 8103 series), computed on the signal
weighted with :func:`vibkit.signal.weighting.frequency_weighting` (Wk vertical, Wd horizontal,
ISO 2631-1) or on a 10 Hz low-passed signal.  Pure numpy/scipy; the recording-level orchestration
is :mod:`vibkit.diagnose.ride`.

Definitions.  The ISO 18738 texts (and ISO/DIS 18738:2001, of which only the cover is public)
were not available to us: what follows is the convention as ride-quality practice describes it
(peak-to-peak values are the differences between adjacent peaks of opposite sign, one per half
cycle between zero crossings; A95 is the value that 95 % of them do not exceed), made exact here:

* a **half-cycle** is a maximal run of samples of one sign (a sample exactly 0 belongs to the run
  before it); its **peak** is its sample of largest magnitude;
* the **peak-to-peak values** are ``|p_i| + |p_{i+1}|`` for every pair of adjacent half-cycles (one
  per zero crossing, so N half-cycles give N - 1 values); the first and the last half-cycle of the
  analysed segment are incomplete and are dropped before pairing;
* **max pk-pk** is the largest of them; **A95** is the smallest peak-to-peak value that at least
  95 % of the values do not exceed (the empirical quantile, ``numpy.quantile(...,
  method="inverted_cdf")``): a value of the record, never an interpolation between two.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal

from ._checks import as_signal, check_fs, fill_nan

__all__ = [
    "LOWPASS_HZ",
    "PeakToPeak",
    "NoIncline",
    "RideSegment",
    "a95",
    "detect_ride_segment",
    "incline_from_vertical_speed",
    "level_run_from_velocity",
    "level_walk_segment",
    "half_cycle_peaks",
    "lowpass_10hz",
    "peak_to_peak",
    "peak_to_peak_values",
]

#: corner of the low-pass that ISO 18738 applies to lift acceleration and that meters offer as the
#: "unweighted" vibration channel [Hz]
LOWPASS_HZ = 10.0
#: the steepest escalator incline (EN 115-1: 30 deg, 35 deg for a rise up to 6 m): a sensor tilting with the chain
#: sees gravity's along-travel component move by at most g sin(35 deg) = 5.6 m/s^2; a move beyond this margin over
#: it is a sensor turned over (a wrist, a phone in a hand), not an incline [m/s^2]
MAX_TILT = 9.80665 * 0.5736 * 1.15


def half_cycle_peaks(x) -> tuple[np.ndarray, np.ndarray]:
    """Signed peak and its index of every complete half-cycle of ``x`` (see module docstring).

    Parameters
    ----------
    x : array_like, 1-D
        Zero-mean signal (a weighted or high-passed acceleration). [any unit]

    Returns
    -------
    peaks : numpy.ndarray
        Signed peak of each complete half-cycle, in time order. [x]
    index : numpy.ndarray of int
        Sample index of each peak.
    """
    x = as_signal(x)
    if x.ndim != 1:
        raise ValueError(f"Parameter x must be 1-D, got shape {x.shape}.")
    x = fill_nan(x)
    from .kernels import _half_cycle_peak_index  # numba on the first use, not with the package

    first = _half_cycle_peak_index(x)
    return x[first], first


def peak_to_peak_values(x) -> np.ndarray:
    """Peak-to-peak values of adjacent half-cycles: ``|p_i| + |p_{i+1}|`` [x] (one per zero crossing).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0, 2, 0.001)
    >>> v = peak_to_peak_values(0.3 * np.sin(2 * np.pi * 5 * t + 0.1))
    >>> bool(np.allclose(v, 0.6, rtol=1e-3)), v.size
    (True, 18)
    """
    p, _ = half_cycle_peaks(x)
    if p.size < 2:
        return np.zeros(0)
    return np.abs(p[:-1]) + np.abs(p[1:])


def a95(values) -> float:
    """The smallest value that at least 95 % of ``values`` do not exceed (ISO 18738 A95) [values].

    Raises
    ------
    ValueError
        ``values`` is empty.
    """
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        raise ValueError("Parameter values is empty: no peak-to-peak value (fewer than three zero crossings).")
    return float(np.quantile(v, 0.95, method="inverted_cdf"))


@dataclass(frozen=True)
class PeakToPeak:
    """Peak-to-peak summary of one signal.

    Attributes
    ----------
    max : float
        Largest peak-to-peak value. [x]
    a95 : float
        A95 (module docstring). [x]
    rms : float
        Root mean square of the signal about zero. [x]
    peak : float
        Largest absolute sample. [x]
    n_values : int
        Number of peak-to-peak values (half-cycle pairs).
    time_of_max_s : float
        Time of the second peak of the largest pair, from the start of the signal. [s]
    """

    max: float
    a95: float
    rms: float
    peak: float
    n_values: int
    time_of_max_s: float

    def as_dict(self) -> dict:
        return {
            "max_pk_pk": self.max,
            "a95": self.a95,
            "rms": self.rms,
            "peak": self.peak,
            "n_values": self.n_values,
            "time_of_max_s": self.time_of_max_s,
        }


def peak_to_peak(x, fs) -> PeakToPeak:
    """Max peak-to-peak, A95, r.m.s. and peak of a (weighted, zero-mean) signal.

    Parameters
    ----------
    x : array_like, 1-D
        Signal over the segment to assess. [any unit]
    fs : float
        Sample rate. [Hz]

    Returns
    -------
    PeakToPeak

    Raises
    ------
    ValueError
        Fewer than two complete half-cycles (nothing to pair).
    """
    fs = check_fs(fs)
    x = as_signal(x)
    p, i = half_cycle_peaks(x)
    if p.size < 2:
        raise ValueError(
            f"Parameter x ({x.size} samples) has fewer than two complete half-cycles: no "
            "peak-to-peak value (a constant or one-signed signal; remove its mean)."
        )
    v = np.abs(p[:-1]) + np.abs(p[1:])
    k = int(np.argmax(v))
    return PeakToPeak(
        max=float(v[k]),
        a95=a95(v),
        rms=float(np.sqrt(np.mean(x * x))),
        peak=float(np.max(np.abs(x))),
        n_values=int(v.size),
        time_of_max_s=float(i[k + 1] / fs),
    )


def lowpass_10hz(x, fs, *, axis=-1, highpass_hz=0.4):
    """The "10 Hz" channel: band-limited like the weightings at ``highpass_hz`` (2nd-order
    Butterworth, removes gravity and offsets) and low-passed at 10 Hz (4th-order Butterworth), causal.

    Parameters
    ----------
    x : array_like
        Acceleration. [m/s^2]
    fs : float
        Sample rate (above 20 Hz). [Hz]
    axis : int
    highpass_hz : float
        Band-limiting high-pass [Hz]; 0.4 Hz as in ISO 2631-1.

    Returns
    -------
    numpy.ndarray
        [x]

    Notes
    -----
    ISO 18738-1 low-passes lift acceleration at 10 Hz to assess acceleration and jerk, and meters
    report peak-to-peak vibration on such a channel as well as on the weighted one; the filter
    order here (4th-order Butterworth) is our choice: the standard's text was not available to us.
    """
    fs = check_fs(fs)
    if fs <= 2.0 * LOWPASS_HZ:
        raise ValueError(
            f"Parameter fs={fs:g} Hz is too low for a {LOWPASS_HZ:g} Hz low-pass (need > {2 * LOWPASS_HZ:g} Hz)."
        )
    x = as_signal(x, axis=axis)
    lp = scipy.signal.butter(4, LOWPASS_HZ, btype="low", fs=fs, output="sos")
    hp = scipy.signal.butter(2, highpass_hz, btype="high", fs=fs, output="sos")
    return scipy.signal.sosfilt(np.vstack([hp, lp]), x, axis=axis)


@dataclass(frozen=True)
class RideSegment:
    """The incline of a ride, found from a record.

    Attributes
    ----------
    start_s, end_s : float
        Times from the start of the record. [s]
    method : str
        ``"vertical speed"``, ``"gravity component"``, ``"speed channel"`` or ``"given"``.
    plateau : float
        The incline's level of the quantity used (vertical speed [m/s] or gravity component
        [m/s^2]); NaN when given.
    note : str
    """

    start_s: float
    end_s: float
    method: str
    plateau: float = float("nan")
    note: str = ""

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s


def _longest_run(mask):
    """(start, stop) indices of the longest run of True in ``mask`` (stop exclusive), or None."""
    if not mask.any():
        return None
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    k = int(np.argmax(stops - starts))
    return int(starts[k]), int(stops[k])


#: an incline cut by an end of the simulated time and shorter than this (the shortest ride weighed) is none [s]:
#: a scene that starts with its step at the top of the incline rides it for a tenth of a second (its ride is one
#: loop later)
MIN_INCLINE_AT_AN_END_S = 0.5
#: the Kolmogorov distribution's 1 % point: a Brownian bridge's largest excursion exceeds 1.628 of its scale in
#: one record of a hundred
BRIDGE_1PCT = 1.628
#: where the vertical channel's own noise is read for the integrated speed's wander [Hz]: above the transition
#: curves' content (seconds long), below a chain's link pass and a person's gait
NOISE_BAND_HZ = (0.5, 2.0)


def integrated_noise(x, fs, band=NOISE_BAND_HZ) -> float:
    """Scale of the wander [m/s] of the integral of an acceleration's noise over its record: the random walk's
    sigma at the record's end, ``sqrt(S(0) T)``, with ``S`` the noise's two-sided spectral density
    [(m/s^2)^2/Hz] read as flat from ``band`` (the median of a Welch spectrum there, corrected to its mean for
    chi-square scatter) and ``T`` the record's length [s].  After the end-to-end drift is removed the integral is
    a Brownian bridge of this scale, whose largest excursion exceeds :data:`BRIDGE_1PCT` of it in 1 % of
    records."""
    x = np.asarray(x, dtype=float)
    nper = int(min(x.size, round(8.0 * fs)))
    f, p = scipy.signal.welch(x - x.mean(), fs, nperseg=nper)
    sel = (f >= band[0]) & (f <= band[1])
    if not sel.any():
        return 0.0
    k = max(1.0, 2.0 * x.size / nper - 1.0)  # Welch averages (half-overlapping): each bin ~ chi-square of 2k dof
    median_to_mean = (1.0 - 2.0 / (9.0 * k)) ** 3
    s_two = 0.5 * float(np.median(p[sel])) / median_to_mean
    return float(np.sqrt(s_two * x.size / fs))


class NoIncline(ValueError):
    """A simulated record in which the step reaches no incline (it rises only round a head)."""


def incline_from_vertical_speed(vz, fs, *, min_speed=0.05, down=False):
    """The incline of a ride from a step's vertical speed ``vz`` [m/s] (a simulation's, exact): the longest
    rise above ``min_speed`` where the speed holds (most of it within 10 % of its median, v sin(alpha)),
    not a turn round a head, where it peaks at the chain's speed for a moment and is an arch (about an
    eighth of it within 10 %); the segment is where it exceeds half that median. ``down``: the steps travel
    down, and the incline is the longest such descent (the rise is the return strand's, under the steps).

    Returns
    -------
    RideSegment
        ``method = "speed channel"``, ``plateau`` the median vertical speed on the incline [m/s] (negative down).

    Raises
    ------
    NoIncline
        No rise that holds its speed (the record reaches no incline).
    """
    way = "down" if down else "up"
    vz = -np.asarray(vz, dtype=float) if down else np.asarray(vz, dtype=float)
    longest = _longest_run(vz > min_speed)
    part = vz[longest[0] : longest[1]] if longest else np.zeros(1)
    plateau = float(np.median(part))
    if longest is None or np.mean(np.abs(part - plateau) < 0.1 * plateau) < 0.5:
        raise NoIncline(
            f"the simulated step does not ride {way} the incline in {vz.size / fs:.3g} s (it "
            f"{'descends' if down else 'rises'} only round a head, where its vertical speed does not hold): simulate "
            "longer (--duration) or give the segment (--segment)"
        )
    a, b = _longest_run(part > 0.5 * plateau)
    a, b = a + longest[0], b + longest[0]
    if (a == 0 or b == vz.size) and (b - a) / fs < MIN_INCLINE_AT_AN_END_S:
        raise NoIncline(
            f"the simulated step rides the incline for {(b - a) / fs:.2g} s only, at the "
            f"{'start' if a == 0 else 'end'} of the {vz.size / fs:.3g} s simulated: simulate longer (--duration) or "
            "give the segment (--segment)"
        )
    note = f"vertical speed {(-plateau if down else plateau):+.3g} m/s of the simulated roller ({way} the incline)"
    if a == 0 or b == vz.size:
        note += "; the incline reaches an end of the simulated time (simulate longer: --duration)"
    return RideSegment(
        start_s=a / fs, end_s=b / fs, method="speed channel", plateau=-plateau if down else plateau, note=note
    )


def level_run_from_velocity(vx, vz, fs, *, backward=False, t0=0.0):
    """The ride of a level moving walk from a pallet's horizontal and vertical speeds ``vx``, ``vz`` [m/s] (a
    simulation's, exact): the longest span in which the pallet runs forward (``backward``: the walk set to run
    the other way, towards -x) at more than half its median forward speed there while its vertical speed stays
    under 2 % of it: the top run between the heads, where the passengers stand (no incline to find). ``t0`` [s]:
    the time of the first sample, added to the segment's times.

    Returns
    -------
    RideSegment
        ``method = "speed channel"``, ``plateau`` the median forward speed on the run [m/s].

    Raises
    ------
    NoIncline
        The pallet never runs forward on the level (it is on the return run, or round a head, all the time).
    """
    fwd = -np.asarray(vx, dtype=float) if backward else np.asarray(vx, dtype=float)
    vz = np.abs(np.asarray(vz, dtype=float))
    on = (fwd > 0.0) & (vz < 0.02 * np.abs(fwd))  # within 1.1 deg of the level: a head's arc ends R/50 from it
    longest = _longest_run(on)
    if longest is None:
        raise NoIncline(
            f"the simulated pallet does not ride the walk's top run in {fwd.size / fs:.3g} s: simulate longer "
            "(--duration) or give the segment (--segment)"
        )
    plateau = float(np.median(fwd[longest[0] : longest[1]]))
    a, b = _longest_run(on & (fwd > 0.5 * plateau))
    if (a == 0 or b == fwd.size) and (b - a) / fs < MIN_INCLINE_AT_AN_END_S:
        raise NoIncline(
            f"the simulated pallet rides the walk's top run for {(b - a) / fs:.2g} s only, at the "
            f"{'start' if a == 0 else 'end'} of the {fwd.size / fs:.3g} s simulated: simulate longer (--duration) "
            "or give the segment (--segment)"
        )
    note = f"a level walk: the simulated pallet on the top run at {plateau:.3g} m/s, no climb"
    if a == 0 or b == fwd.size:
        note += "; the top run reaches an end of the simulated time (simulate longer: --duration)"
    return RideSegment(start_s=t0 + a / fs, end_s=t0 + b / fs, method="speed channel", plateau=plateau, note=note)


def level_walk_segment(duration_s):
    """The ride of a recording on a level moving walk: the whole record of ``duration_s`` [s] (no climb to find)."""
    return RideSegment(
        start_s=0.0,
        end_s=float(duration_s),
        method="whole record",
        note="a level moving walk: no climb to find, the whole record is the ride (--segment: the part on it)",
    )


def detect_ride_segment(
    fs, *, vertical=None, along=None, lowpass_hz=0.3, edge_s=1.0, min_vertical_speed=0.05, min_tilt=0.5
) -> RideSegment:
    """Find the incline (start and end) of a step-riding accelerometer record.

    Two methods, tried in this order:

    * **gravity component** (a sensor that tilts with the chain, measuring along the guide, as
      ``accel_step`` or a sensor on the chain links): the low-passed ``along`` acceleration moves
      from its landing level by ``g sin(incline)`` (4.9 m/s^2 at 30 deg) on the incline; the incline
      is where it is further than half that step from the level of the first ``edge_s`` seconds.
      Used when the step exceeds ``min_tilt``.
    * **vertical speed** (a sensor on the step tread, axes horizontal and vertical): the
      low-passed ``vertical`` acceleration, minus its mean over the first and last ``edge_s``
      seconds, is integrated to the vertical speed; a linear drift is removed so that the speed is
      zero at both ends (the record starts and ends on the landings); the incline is the longest
      stretch where the speed exceeds half its extreme (``v sin(incline)``, 0.26 m/s at 0.52 m/s
      and 30 deg), i.e. it starts and ends inside the transition curves, where the vertical speed
      is half the incline's.

    Parameters
    ----------
    fs : float
        Sample rate. [Hz]
    vertical : array_like, optional
        Vertical acceleration (z, up; gravity included or not). [m/s^2]
    along : array_like, optional
        Acceleration along the direction of travel (x). [m/s^2]
    lowpass_hz : float
        Corner of the zero-phase low-pass that keeps the trend (transition curves last seconds). [Hz]
    edge_s : float
        Length at each end taken as landing. [s]
    min_vertical_speed : float
        Smallest vertical speed accepted as an incline. [m/s]
    min_tilt : float
        Smallest gravity-component step accepted as a tilt. [m/s^2]

    Returns
    -------
    RideSegment

    Raises
    ------
    ValueError
        No channel given, a record shorter than ``4 edge_s``, or no incline found (the message says
        what was seen and suggests giving the segment).

    Notes
    -----
    Failure modes: a record that starts or ends on the incline (the speed is then not zero at both
    ends: the drift removal tilts the plateau, and the half-level crossings move); a vertical axis
    that is not vertical (a sensor mounted on its side: give the right channel); accelerometer
    offset drifting during the ride (removed only if linear); an escalator running down (the
    speed is negative: handled, the extreme may have either sign); several inclines in one record
    (the longest is taken).
    """
    fs = check_fs(fs)
    if vertical is None and along is None:
        raise ValueError("detect_ride_segment needs the vertical or the along-travel acceleration.")
    sos = scipy.signal.butter(2, lowpass_hz, btype="low", fs=fs, output="sos")
    n_edge = max(1, int(round(edge_s * fs)))
    notes = []
    if along is not None:
        a = as_signal(along, "along")
        if a.size < 4 * n_edge:
            raise ValueError(
                f"record of {a.size / fs:.3g} s is too short to find a ride segment (need at least {4 * edge_s:g} s)."
            )
        trend = scipy.signal.sosfiltfilt(sos, a)
        base = float(np.mean(trend[:n_edge]))
        dev = trend - base
        k = int(np.argmax(np.abs(dev)))
        step = float(dev[k])
        if abs(step) > MAX_TILT:
            raise ValueError(
                f"no incline found: the along-travel gravity component moves by {step:+.3g} m/s^2, more than an "
                f"escalator's steepest incline gives (g sin 35 deg = 5.6 m/s^2): the sensor turned over rather than "
                "rode an incline; is this a step's recording? Give the segment as --segment START:END"
            )
        if abs(step) >= min_tilt:
            run = _longest_run(np.abs(dev) > 0.5 * abs(step))
            i0, i1 = run
            return RideSegment(
                start_s=i0 / fs,
                end_s=i1 / fs,
                method="gravity component",
                plateau=step,
                note=f"along-travel gravity component moves by {step:+.3g} m/s^2 on the incline",
            )
        notes.append(f"along-travel trend moves by at most {abs(step):.2g} m/s^2: no tilt")
    if vertical is None:
        raise ValueError(
            "no incline found: " + "; ".join(notes) + " (give the vertical channel, or the segment "
            "as --segment START:END)"
        )
    z = as_signal(vertical, "vertical")
    if z.size < 4 * n_edge:
        raise ValueError(
            f"record of {z.size / fs:.3g} s is too short to find a ride segment (need at least {4 * edge_s:g} s)."
        )
    zt = scipy.signal.sosfiltfilt(sos, z)
    rest = 0.5 * (np.mean(zt[:n_edge]) + np.mean(zt[-n_edge:]))
    v = np.cumsum(zt - rest) / fs
    # linear drift: speed zero on both landings
    t = np.arange(z.size)
    v0, v1 = np.mean(v[:n_edge]), np.mean(v[-n_edge:])
    v = v - (v0 + (v1 - v0) * (t - n_edge / 2) / max(z.size - n_edge, 1))
    k = int(np.argmax(np.abs(v)))
    peak = float(v[k])
    if abs(peak) < min_vertical_speed:
        raise ValueError(
            f"no incline found: the vertical speed integrated from the vertical channel stays within "
            f"{abs(peak):.3g} m/s (< {min_vertical_speed:g} m/s) -- is that channel vertical, and does "
            "the record start and end on the landings? Give the segment as --segment START:END."
        )
    wander = BRIDGE_1PCT * integrated_noise(z, fs)
    if abs(peak) < wander:
        raise ValueError(
            f"no incline found: the vertical speed integrated from the vertical channel reaches {abs(peak):.3g} m/s, "
            f"which the channel's own noise gives by chance (its integral wanders up to {wander:.2g} m/s over "
            f"{z.size / fs:.0f} s in one record of a hundred): no incline stands out of the noise. Give the segment "
            "as --segment START:END."
        )
    i0, i1 = _longest_run(np.sign(peak) * v > 0.5 * abs(peak))
    if i0 == 0 or i1 == z.size:
        notes.append("the incline reaches an end of the record: it may start or end on the incline")
    return RideSegment(
        start_s=i0 / fs,
        end_s=i1 / fs,
        method="vertical speed",
        plateau=peak,
        note="; ".join(notes + [f"vertical speed {peak:+.3g} m/s on the incline"]),
    )
