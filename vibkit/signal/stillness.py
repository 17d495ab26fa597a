"""Where the person carrying a phone stands still: the walking band of the acceleration's magnitude.

Walking puts 1-3 m/s^2 r.m.s. into 0.5-3 Hz of ``|a|`` (the step frequency, about 2 Hz, and its
harmonic); standing, also on a moving escalator, leaves 0.03-0.1 m/s^2 (the phone in the hand sways).
The magnitude does not depend on how the phone is held.  Where the reading has gravity removed (a phone app's
"linear acceleration": no steady part, see :func:`gravity_removed`), ``|a|`` rectifies the step, which then shows
at twice its rate, out of the band, and a walk would read as standing: there the level is the walking band of the
three axes together (the step's whole acceleration, not only its part along gravity).  A span is *still* from where the walking band's
r.m.s. over ``window_s`` falls under ``threshold`` to where it rises over the higher ``leave`` and stays there
for a step or more (hysteresis: a passenger shifting on a step does not end a ride), at least ``min_s`` long.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage, signal

from ._checks import check_fs

__all__ = [
    "WALKING_BAND_HZ",
    "STILL_THRESHOLD",
    "LEAVE_THRESHOLD",
    "STEP_PERIOD_S",
    "gravity_removed",
    "walking_level",
    "still_spans",
]

#: the band of |a| that walking fills [Hz]
WALKING_BAND_HZ = (0.5, 3.0)
#: walking band r.m.s. under which a person stands still [m/s^2]: measured on the ADVIO phone walks,
#: standing 0.03-0.13, walking 0.9-1.6, stepping on or off 0.2-0.6
STILL_THRESHOLD = 0.25
#: walking band r.m.s. over which, held for a step period, the person walks again [m/s^2]: the ADVIO development
#: walks between rides hold a median of 0.41-0.75 and reach 0.7-1.1; a passenger shifting on a step reaches 0.3-0.35
LEAVE_THRESHOLD = 0.4
#: how long the walking band must stay over :data:`LEAVE_THRESHOLD` to end a still span [s]: one step (about 2 Hz)
STEP_PERIOD_S = 0.5


def gravity_removed(acc, fs, *, window_s=2.0) -> bool:
    """Whether the accelerometer's three axes ``acc`` (shape (3, N), m/s^2, at ``fs``) have gravity removed.

    Gravity is the reading's steady part: its running mean over ``window_s`` keeps about 9.81 m/s^2 and most of
    ``|a|``.  With gravity removed the running mean is what motion and the sensor's bias leave: under half of the
    median ``|a|``, or under 0.5 m/s^2 (on the Sensor Logger walks tried, 0.12-0.25 of ``|a|``; a phone lying
    still: 0.014 of 0.03 m/s^2)."""
    acc = np.asarray(acc, dtype=float)
    ok = np.all(np.isfinite(acc), axis=0)
    if ok.sum() < 3:
        return False
    a = acc[:, ok]
    w = max(int(round(window_s * check_fs(fs))), 1)
    steady = float(np.median(np.sqrt(np.sum(ndimage.uniform_filter1d(a, w, axis=1, mode="nearest") ** 2, axis=0))))
    mag = float(np.median(np.sqrt(np.sum(a**2, axis=0))))
    return steady < 0.5 * mag or steady < 0.5


def walking_level(acc, fs, *, band=WALKING_BAND_HZ, window_s=2.0):
    """R.m.s. of the acceleration magnitude's walking band in a centred running window [units of ``acc``].

    Parameters
    ----------
    acc : array_like, shape (3, N)
        The three axes of an accelerometer [m/s^2], sampled uniformly at ``fs``.
    fs : float
        Sample rate [Hz].
    band : (float, float)
        The walking band [Hz].
    window_s : float
        Length of the running r.m.s. [s].
    """
    fs = check_fs(fs)
    acc = np.asarray(acc, dtype=float)
    if acc.ndim != 2 or acc.shape[0] != 3:
        raise ValueError(f"acc has shape {acc.shape}; expected (3, N): the three axes of one accelerometer")
    mag = np.sqrt(np.sum(acc**2, axis=0))
    hi = min(band[1], 0.45 * fs)
    sos = signal.butter(4, [band[0], hi], "bandpass", fs=fs, output="sos")
    if mag.size <= 3 * 2 * sos.shape[0] * 3:
        return np.full(mag.size, np.nan)
    if gravity_removed(acc, fs):  # |a| would rectify the step: the band of the three axes together
        y2 = np.sum(signal.sosfiltfilt(sos, acc, axis=1) ** 2, axis=0)
    else:
        y2 = signal.sosfiltfilt(sos, mag) ** 2
    w = max(int(round(window_s * fs)), 1)
    return np.sqrt(ndimage.uniform_filter1d(y2, w, mode="nearest"))


def still_spans(level, fs, *, threshold=STILL_THRESHOLD, leave=LEAVE_THRESHOLD, dwell_s=STEP_PERIOD_S, min_s=8.0):
    """Spans ``(start, stop)`` (sample indices, stop exclusive) of at least ``min_s`` seconds in which the person
    stands still: entered where ``level`` falls under ``threshold``, left only where it stands over ``leave`` for
    ``dwell_s`` or longer (walking resumes; the span ends where that run starts).  A passenger who shifts on a step
    (the level over ``threshold`` but under ``leave``, or over it for less than a step) does not cut the span;
    samples that are not finite (a gap) always end it.  ``leave=threshold, dwell_s=0`` is a single threshold."""
    fs = check_fs(fs)
    level = np.asarray(level, dtype=float)
    if leave < threshold:
        raise ValueError(f"leave {leave:g} is under threshold {threshold:g}; expected leave >= threshold")
    over = ~(level <= leave)  # NaN and inf count as over
    d = np.diff(np.concatenate(([0], over.astype(np.int8), [0])))
    dwell = max(int(round(dwell_s * fs)), 1)
    walking = ~np.isfinite(level)
    for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)):
        if b - a >= dwell:
            walking[a:b] = True
    d = np.diff(np.concatenate(([1], walking.astype(np.int8), [1])))
    out = []
    for a, b in zip(np.flatnonzero(d == -1), np.flatnonzero(d == 1)):
        quiet = np.flatnonzero(level[a:b] < threshold)
        if quiet.size and (b - (a + quiet[0])) / fs >= min_s:
            out.append((int(a + quiet[0]), int(b)))
    return out
