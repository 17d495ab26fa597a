"""Where the person carrying a phone stands still: the walking band of the acceleration's magnitude.

Walking puts 1-3 m/s^2 r.m.s. into 0.5-3 Hz of ``|a|`` (the step frequency, about 2 Hz, and its
harmonic); standing, also on a moving escalator, leaves 0.03-0.1 m/s^2 (the phone in the hand sways).
The magnitude does not depend on how the phone is held.  A span is *still* where the walking band's
r.m.s. over ``window_s`` stays under ``threshold`` for at least ``min_s`` seconds.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage, signal

from ._checks import check_fs

__all__ = ["WALKING_BAND_HZ", "STILL_THRESHOLD", "walking_level", "still_spans"]

#: the band of |a| that walking fills [Hz]
WALKING_BAND_HZ = (0.5, 3.0)
#: walking band r.m.s. under which a person stands still [m/s^2]: measured on the ADVIO phone walks,
#: standing 0.03-0.13, walking 0.9-1.6, stepping on or off 0.2-0.6
STILL_THRESHOLD = 0.25


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
    y = signal.sosfiltfilt(sos, mag)
    w = max(int(round(window_s * fs)), 1)
    return np.sqrt(ndimage.uniform_filter1d(y**2, w, mode="nearest"))


def still_spans(level, fs, *, threshold=STILL_THRESHOLD, min_s=8.0):
    """Spans ``(start, stop)`` (sample indices, stop exclusive) where ``level`` stays under ``threshold`` for at
    least ``min_s`` seconds."""
    fs = check_fs(fs)
    quiet = np.asarray(level) < threshold
    d = np.diff(np.concatenate(([0], quiet.astype(np.int8), [0])))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return [(int(a), int(b)) for a, b in zip(starts, stops) if (b - a) / fs >= min_s]
