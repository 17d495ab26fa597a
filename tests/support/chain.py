"""Synthetic chain signals: harmonics of the link-pass frequency f = v / L, with noise where asked.

Every function computes its sum term by term in the order the tests were written with, so a test that
moved here reads the same bits it read before.
"""

from __future__ import annotations

import numpy as np

AMPS = (1.0, 0.5, 0.3)  # the usual harmonic amplitudes of a link-pass family
PITCH = 0.13333  # m, a 133 mm escalator chain
SPEED = 0.5  # m/s


def family(t, f, amps=AMPS, phases=None):
    """sum_k a_k cos(2 pi (k+1) f t + phi_k): the link-pass family at ``f`` [Hz] on times ``t`` [s]."""
    phases = phases if phases is not None else np.zeros(len(amps))
    return sum(a * np.cos(2 * np.pi * (k + 1) * f * t + phases[k]) for k, a in enumerate(amps))


def family_of_phase(phi, amps=AMPS, phases=None):
    """sum_k a_k cos((k+1) phi + phi_k): the family on a given link-pass phase ``phi`` [rad]."""
    phases = phases if phases is not None else np.zeros(len(amps))
    return sum(a * np.cos((k + 1) * phi + phases[k]) for k, a in enumerate(amps))


def noise_sigma(amps, snr_db):
    """White-noise standard deviation that puts the family ``amps`` at ``snr_db`` per sample."""
    return np.sqrt(sum(a * a / 2 for a in amps) / 10 ** (snr_db / 10))


def noisy_family(n, fs, f, rng, snr_db, amps=AMPS):
    """``n`` samples at ``fs`` of the family at ``f`` (phases 0.7 k) in white noise at ``snr_db``."""
    t = np.arange(n) / fs
    x = family(t, f, amps, phases=[0.7 * k for k in range(len(amps))])
    return x + noise_sigma(amps, snr_db) * rng.standard_normal(n)


def chain(f, seconds=30.0, fs=200.0, noise=0.1, seed=1):
    """The family (1, 0.5, 0.3) at ``f`` with phases (0, 1, 2) in white noise of standard deviation ``noise``."""
    t = np.arange(int(seconds * fs)) / fs
    x = family(t, f, AMPS, phases=(0, 1, 2))
    return x + noise * np.random.default_rng(seed).standard_normal(t.size)


def wandering(duration, fs, period, amp, snr_db, kind, seed, pitch=PITCH, v0=SPEED):
    """A chain under a wandering speed v(t) = v0 (1 + w(t)), |w| <= amp, in white noise at ``snr_db``.

    ``kind`` "sine": w a sine of ``period`` [s] at a random phase; otherwise a random walk through knots
    every period / 4, smoothed by linear interpolation. ``seed`` is a seed or a numpy Generator. Returns
    (signal, mean speed over the record as a wheel on the steps measures it, pitch).
    """
    rng = np.random.default_rng(seed)
    n = int(duration * fs)
    t = np.arange(n) / fs
    if kind == "sine":
        w = amp * np.sin(2 * np.pi * t / period + rng.uniform(0, 2 * np.pi))
    else:
        m = int(duration / period * 4) + 2
        knots = np.cumsum(rng.standard_normal(m))
        w = np.interp(t, np.linspace(0, duration, m), knots - knots.mean())
        w = amp * w / np.max(np.abs(w))
    v = v0 * (1 + w)
    f = v / pitch
    phi = 2 * np.pi * np.concatenate(([0.0], np.cumsum((f[1:] + f[:-1]) / 2) / fs))
    amps = (1.0, 0.5, 0.3)
    x = family_of_phase(phi, amps, phases=[0.7 * k for k in range(len(amps))])
    x = x + noise_sigma(amps, snr_db) * rng.standard_normal(n)
    return x, float(np.trapezoid(v, t) / t[-1]), pitch


def random_phase_family(t, f, rng, amps=AMPS, noise=1.0):
    """White noise of standard deviation ``noise``, then the family at ``f`` with phases drawn from ``rng``."""
    x = noise * rng.standard_normal(t.size)
    for k, a in enumerate(amps, 1):
        x += a * np.cos(2 * np.pi * k * f * t + rng.uniform(0, 2 * np.pi))
    return x
