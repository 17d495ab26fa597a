"""Synthetic sources whose frequency drifts: a linear drift, a mean-reverting random wander, a gait-like cadence.

Each returns ``(x, centre, record_mean)``: the samples, the frequency the source wanders about [Hz] (what a
recording at another time would measure on average) and the mean frequency over this record (total phase over
the time) [Hz].  ``rng`` is a numpy Generator.
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from .chain import family_of_phase, noise_sigma

#: harmonic amplitudes of a running cadence seen by a wrist sensor: a strong step line and its harmonics
GAIT_AMPS = (1.0, 0.6, 0.35, 0.2)


def _on_frequency(f, fs, amps, snr_db, rng):
    """The harmonic family ``amps`` on the instantaneous frequency ``f`` [Hz] (random phases) in white noise at
    ``snr_db`` per sample; returns ``(x, record_mean)``."""
    phi = 2 * np.pi * np.concatenate(([0.0], np.cumsum((f[1:] + f[:-1]) / 2) / fs))
    x = family_of_phase(phi, amps, phases=rng.uniform(0, 2 * np.pi, len(amps)))
    x = x + noise_sigma(amps, snr_db) * rng.standard_normal(f.size)
    return x, float(phi[-1] / (2 * np.pi * (f.size - 1) / fs))


def linear_drift(duration, fs, f_mid, drift, snr_db, rng, amps=(1.0, 0.5, 0.3)):
    """A family whose frequency runs linearly from ``f_mid (1 - drift / 2)`` to ``f_mid (1 + drift / 2)`` over
    ``duration`` [s] at ``fs`` [Hz]; ``drift`` relative.  The centre is ``f_mid`` (the mid-record frequency)."""
    t = np.arange(int(duration * fs)) / fs
    f = f_mid * (1 + drift * (t / t[-1] - 0.5))
    x, mean = _on_frequency(f, fs, amps, snr_db, rng)
    return x, float(f_mid), mean


def ou_wander(duration, fs, f_c, sd, tau, snr_db, rng, amps=(1.0, 0.5, 0.3)):
    """A family on ``f_c (1 + w(t))``, ``w`` an Ornstein-Uhlenbeck process (standard deviation ``sd``, relative;
    correlation time ``tau`` [s]) started in its stationary state: a random wander about ``f_c`` with no end,
    of which the record is one window."""
    n = int(duration * fs)
    a = np.exp(-1.0 / (fs * tau))
    xi = rng.standard_normal(n)
    w = scipy.signal.lfilter([sd * np.sqrt(1 - a * a)], [1.0, -a], xi, zi=[a * sd * rng.standard_normal()])[0]
    x, mean = _on_frequency(f_c * (1 + w), fs, amps, snr_db, rng)
    return x, float(f_c), mean


def gait(duration, fs, rng, cadence=2.72, wander=0.01, tau=90.0, snr_db=0.0):
    """A running cadence ``cadence`` [Hz] wandering by +-``wander`` (two standard deviations) over minutes
    (correlation time ``tau`` [s]), with harmonics :data:`GAIT_AMPS` and white noise at ``snr_db`` per sample:
    what a wrist sensor on a runner records (2.69-2.75 Hz between 5-minute windows)."""
    return ou_wander(duration, fs, cadence, wander / 2, tau, snr_db, rng, amps=GAIT_AMPS)
