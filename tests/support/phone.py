"""A link-pass line added to a phone's channels at a stated level over each channel's own floor.

A phone's channels are in different units with floors far apart (standing in ADVIO: the accelerometer's axes
2e-4-5e-3 (m/s^2)^2/Hz, the gyroscope's 1e-5-2e-4 (rad/s)^2/Hz, up to 23 dB between two axes), so a line's
share of the channels is a share of their *levels over their own floors*, not of their amplitudes in one unit.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

__all__ = ["welch_level", "add_line", "floor_at_line_db", "shares"]

#: the level's reference band [Hz]: the median of an 8 s Welch spectrum over it is the floor
FLOOR_BAND_HZ = (1.5, 10.0)


def welch_level(x, fs, freq, *, local_hz=None):
    """The peak of an 8 s Welch spectrum of ``x`` within 2 % of ``freq`` [Hz] over the spectrum's median of 1.5-10 Hz
    (``local_hz`` None) or of ``freq +- local_hz`` (the floor at the line), in dB."""
    f, p = signal.welch(np.asarray(x, dtype=float) - np.mean(x), fs, nperseg=int(8 * fs))
    sel = (f > FLOOR_BAND_HZ[0]) & (f < FLOOR_BAND_HZ[1]) if local_hz is None else np.abs(f - freq) <= local_hz
    floor = float(np.median(p[sel]))
    peak = float(p[np.abs(f - freq) <= max(0.02 * freq, f[1])].max())
    return 10.0 * math.log10(peak / floor)


def floor_at_line_db(x, fs, freq, *, local_hz=1.0):
    """How far the floor at the line (the median of ``x``'s 8 s Welch spectrum within ``freq +- local_hz``) stands
    under the median of 1.5-10 Hz [dB]: a line's level over the floor at the line is its level over the 1.5-10 Hz
    median plus this (negative where the floor rises near the line, as a phone's handling noise does at 3-5 Hz)."""
    f, p = signal.welch(np.asarray(x, dtype=float) - np.mean(x), fs, nperseg=int(8 * fs))
    band = float(np.median(p[(f > FLOOR_BAND_HZ[0]) & (f < FLOOR_BAND_HZ[1])]))
    local = float(np.median(p[np.abs(f - freq) <= local_hz]))
    return 10.0 * math.log10(band / local)


def _floor_and_gain(x, fs):
    """(median PSD of 1.5-10 Hz, the factor from a tone's amplitude squared to its 8 s Welch peak)."""
    f, p = signal.welch(x - x.mean(), fs, nperseg=int(8 * fs))
    floor = float(np.median(p[(f > FLOOR_BAND_HZ[0]) & (f < FLOOR_BAND_HZ[1])]))
    enbw = 1.5 * fs / int(8 * fs)  # a Hann window's equivalent noise bandwidth [Hz]
    return floor, 1.0 / (2.0 * enbw)


def add_line(still, fs, phase, weights, level_db, rng):
    """``still`` (C x N, the channels without the line) with ``sin(phase + phi_c)`` added to each channel, ``phi_c``
    uniform from ``rng`` (drawn in channel order), at an amplitude that puts channel ``c``'s 8 s Welch peak
    ``level_db + 10 log10(weights[c] / max(weights))`` over that channel's own median of 1.5-10 Hz: the strongest
    channel stands at ``level_db``, the others below it by their weights' ratio."""
    still = np.array(still, dtype=float, copy=True)
    weights = np.asarray(weights, dtype=float)
    top = float(weights.max())
    for c in range(still.shape[0]):
        floor, gain = _floor_and_gain(still[c], fs)
        amp = math.sqrt(floor * 10 ** (level_db / 10) * weights[c] / top / gain)
        still[c] += amp * np.sin(phase + rng.uniform(0, 2 * np.pi))
    return still


def shares(levels_db):
    """The weights that :func:`add_line` needs to reproduce a line measured at ``levels_db`` (each channel's
    :func:`welch_level`): each channel's excess over its floor (the peak less the noise in its bin, ``10**(L/10) - 1``,
    none where the peak is at the floor) over the strongest channel's."""
    excess = np.clip(10.0 ** (np.asarray(levels_db, dtype=float) / 10.0) - 1.0, 0.0, None)
    top = float(excess.max())
    if not top > 0:
        raise ValueError("no channel's level stands over its floor: no line to take a pattern from")
    return excess / top
