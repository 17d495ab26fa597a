"""A roller worn flat: where it rolls on a track, its centre dips toward the track once a turn.

The guide is the path of the rollers' centres (model.md section 1), and a round roller's centre stays
on it. A roller worn flat over a chord d (half-angle beta = asin(d / 2r)) is a circle with that chord
cut off. Rolling on its track it pivots on the flat's two edges: the centre's height above the track
is the cut circle's support, h(phi) = r cos(beta - |phi|) for |phi| < beta and r otherwise, phi the
angle between the flat's outward normal and the direction to the track. The centre dips toward the
track by

    D(phi) = r (1 - cos(beta - |phi|)),    |phi| < beta,

deepest, r (1 - cos beta), when the flat lies on the track. Its velocity toward the track,
D'(phi) phi-dot, rises to v sin(beta) as the leading edge comes down and is -v sin(beta) once the roller
pivots on the other edge: at phi = 0 the leading edge strikes the track and reverses it by
2 v sin(beta), an impact (the knock of a flat roller), once a turn.

Where. On the twelve track segments of the guide, not on the two heads: there the roller sits in a
tooth of the sprocket or on the carriage's wheel and turns with it. The track is on the side of the
guide facing down (the step's weight holds its rollers on their track on both runs). The flat's angle
relative to the track's normal advances by (1/r - s kappa) per metre of travel (kappa the guide's
signed curvature, s = +1 when the track is on the left of the direction of travel), and not at all on
the heads. At the start of a run every flat faces away from its track (phi = pi).

First order. The dip is 0.09 mm for a 5 mm flat on a 35 mm roller. Moving a roller by D across its
track shortens the span of its two links by D^2 / p on a straight run (6e-8 m), so the closure, the
tensioner and the chain's motion are those of the round roller to that order; the knock's impulse is
normal to the track. So the flat is added to the roller's own motion (positions, velocities and
accelerations of the rollers a scene stores), not to the chain's (:func:`flat_motion`). It holds while
the step's weight keeps the roller on the flat's edges: the pivot asks v^2 / r of acceleration toward
the track, which gravity gives up to v = sqrt(g r cos(alpha)) (:func:`flat_speed_limit`; above it the
roller would fly over the flat and land, which is not modelled).

Sampled. The knock is shorter than most output steps (10 ms for a 5 mm flat at 0.5 m/s, 2 ms for 1 mm)
and its impact has no finite value, so no sample of the motion itself would carry it faithfully: a
sample that misses the dip reads nothing. The flat's part of the outputs is therefore the motion as a
sensor records it through a Gaussian anti-alias filter of :data:`FILTER_STEPS` output steps (the dip
convolved with the Gaussian and its two derivatives, :func:`flat_motion`): below the filter's cut-off
the knocks' spectrum is the physical one, (2 pi f)^2 times the dip's Fourier transform per knock, which
does not depend on the roller's tyre or the sensor, while the peak of a knock does (a real accelerometer
reads it through the tyre and its own filter). Position, velocity and acceleration are one filtered
motion, each the derivative of the one before.
"""

from __future__ import annotations

import math

import numpy as np

from ..runtime.kernel import kernel
from .guide import KAPPA, S0, local_frame, local_map, locate

__all__ = ["HEADS", "add_flats", "flat_dip", "flat_motion", "flat_speed_limit"]

#: the guide's segments where a roller sits on a wheel or the sprocket, not on a track (model.md section 1)
HEADS = (6, 13)


def flat_dip(phi, radius, chord):
    """The dip of the centre of a roller of ``radius`` with a flat of ``chord`` toward its track, and its
    first and second derivatives with respect to the flat's angle ``phi`` (wrapped to [-pi, pi)). [m, m/rad,
    m/rad^2]

    ``D'`` jumps from +r sin(beta) to -r sin(beta) at phi = 0 (the impact); at phi = 0 itself it is 0.
    """
    beta = math.asin(chord / (2.0 * radius))
    phi = np.mod(np.asarray(phi, dtype=float) + math.pi, 2.0 * math.pi) - math.pi
    a = np.abs(phi)
    on = a < beta
    d = np.where(on, radius * (1.0 - np.cos(beta - a)), 0.0)
    d1 = np.where(on, -radius * np.sin(beta - a) * np.sign(phi), 0.0)
    d2 = np.where(on, radius * np.cos(beta - a), 0.0)
    return d, d1, d2


def flat_speed_limit(radius, incline_angle, transition_radius, g=9.81):
    """The largest chain speed at which the step's weight keeps a flat roller of ``radius`` on the flat's
    edges on an incline of ``incline_angle`` [rad]: v^2 (1/r + 1/r_t) = g cos(alpha) (the pivot's v^2 / r
    toward the track, and the concave transition's v^2 / r_t away from it). [m/s]"""
    return math.sqrt(g * math.cos(incline_angle) / (1.0 / radius + 1.0 / transition_radius))


@kernel()
def _frames(tab, p0, s0, delta, out):
    """x, z, tx, tz, kappa and 1.0 on a track (0.0 on a head) of the guide point at each s0 (at its delta)."""
    for j in range(s0.size):
        s = s0[j] - math.floor(s0[j] / p0) * p0
        k = locate(tab, s)
        lam = local_map(tab, k, s - tab[k, S0], delta[j])[0]
        x, z, tx, tz = local_frame(tab, k, lam, delta[j])
        out[j, 0] = x
        out[j, 1] = z
        out[j, 2] = tx
        out[j, 3] = tz
        out[j, 4] = tab[k, KAPPA]
        out[j, 5] = 0.0 if (k == HEADS[0] or k == HEADS[1]) else 1.0


#: the sensor's anti-alias filter that the flat's part of the outputs is given through: a Gaussian of
#: this many output steps' standard deviation (-1 dB at 0.17 fs, -3 dB at 0.31 fs, -15 dB at fs / 2)
FILTER_STEPS = 0.6
#: Gauss-Legendre points on each side of the impact, per sample
_GAUSS = np.polynomial.legendre.leggauss(24)


def _knock_kernels(u, sigma):
    """The Gaussian of standard deviation ``sigma`` at ``u`` and its first and second derivatives."""
    g = np.exp(-0.5 * (u / sigma) ** 2) / (sigma * math.sqrt(2.0 * math.pi))
    return g, -u / sigma**2 * g, (u**2 / sigma**4 - 1.0 / sigma**2) * g


def _convolved(u, half, rate, sigma, radius, chord):
    """The dip D(rate tau), |tau| < half, convolved with the Gaussian, and its first and second time
    derivatives, at the times ``u`` from the impact: D * g, D' * g and D'' * g + J g(u), J the jump of D' at
    the impact (-2 r sin(beta) rate). Each integral over the part of the dip within 8 sigma of u, on each
    side of the impact, by Gauss-Legendre (the integrands are smooth there). (3 arrays like u)"""
    x, w = _GAUSS
    out = [np.zeros(u.size) for _ in range(3)]
    for a, b in (
        (np.maximum(-half, u - 8 * sigma), np.minimum(0.0, u + 8 * sigma)),
        (np.maximum(0.0, u - 8 * sigma), np.minimum(half, u + 8 * sigma)),
    ):
        width = np.maximum(b - a, 0.0)
        tau = 0.5 * (a + b)[:, None] + 0.5 * width[:, None] * x[None, :]
        d, d1, d2 = flat_dip(rate * tau, radius, chord)
        g = _knock_kernels(u[:, None] - tau, sigma)[0]
        for o, f in zip(out, (d, rate * d1, rate**2 * d2)):
            o += 0.5 * width * ((f * g) @ w)
    jump = -chord * rate  # -2 r sin(beta) rate
    out[2] += jump * _knock_kernels(u, sigma)[0]
    return out


def flat_motion(tab, p0, t, s0, delta, radius, chord, phase=math.pi, sigma=None):
    """The flat's part of one roller's motion at the samples ``t``, as a sensor with a Gaussian
    anti-alias filter records it. [m, m/s, m/s^2]

    ``tab``, ``p0``: the guide's segment table and undeformed perimeter; ``s0`` (nt,): the roller's
    undeformed-guide coordinate at each sample (unwrapped); ``delta`` (nt,): the tensioner's; ``radius``
    and ``chord`` the roller's and its flat's; ``phase``: the flat's angle at the first sample; ``sigma``:
    the filter's standard deviation [s] (default :data:`FILTER_STEPS` median output steps).

    Each knock (the flat's angle passing 0 on a track, at t_k) is the dip D(phi-dot (t - t_k)) toward the
    track, over |t - t_k| < beta / phi-dot; the outputs are that dip convolved with the Gaussian g and
    its first and second derivatives (the impact is in g''s convolution with the dip: no sample has to
    fall on it). A knock much shorter than the filter gives (2 pi f)^2 A per unit time at frequency f
    below the filter's cut-off, A = 2 r (beta - sin beta) / phi-dot the area of its dip.
    Returns the offsets of position, velocity and acceleration, each (nt, 2), and the flat's angle phi
    at the samples (nt,).
    """
    t = np.asarray(t, dtype=float)
    nt = t.size
    fr = np.empty((nt, 6))
    _frames(tab, float(p0), np.asarray(s0, dtype=float), np.asarray(delta, dtype=float), fr)
    x, z, tx, tz, kap, track = (fr[:, i] for i in range(6))
    # the track's side: +1 on the left of travel where the left normal (-tz, tx) points down
    side = np.where(tx < 0.0, 1.0, -1.0)
    nx, nz = -side * tz, side * tx  # unit normal toward the track
    rate = track * (1.0 / radius - side * kap)  # the flat's turn per metre of travel [rad/m]
    pos, vel, acc = np.zeros((nt, 2)), np.zeros((nt, 2)), np.zeros((nt, 2))
    if nt < 2:
        return pos, vel, acc, np.full(nt, float(phase))
    step = np.hypot(np.diff(x), np.diff(z))  # travel between samples (chord of the arc: < 1e-9 relative)
    dphi = step * 0.5 * (rate[1:] + rate[:-1])
    phi = float(phase) + np.concatenate([[0.0], np.cumsum(dphi)])
    sigma = FILTER_STEPS * float(np.median(np.diff(t))) if sigma is None else float(sigma)
    beta = math.asin(chord / (2.0 * radius))
    # the knocks: phi passes a multiple of 2 pi between samples j and j + 1, on a track
    turns = np.floor(phi / (2.0 * math.pi))
    for j in np.flatnonzero((np.diff(turns) != 0) & (track[:-1] * track[1:] > 0)):
        target = 2.0 * math.pi * turns[j + 1]
        rate_t = dphi[j] / (t[j + 1] - t[j])  # phi-dot over the interval [rad/s]
        if not rate_t > 0:
            continue
        tk = t[j] + (target - phi[j]) / rate_t
        half = beta / rate_t  # the dip lasts 2 beta / phi-dot
        reach = half + 8.0 * sigma
        lo, hi = np.searchsorted(t, [tk - reach, tk + reach])
        if hi <= lo:
            continue
        u = t[lo:hi] - tk
        c0, c1, c2 = _convolved(u, half, rate_t, sigma, radius, chord)
        n = np.array([nx[j], nz[j]]) if track[j] else np.array([nx[j + 1], nz[j + 1]])
        pos[lo:hi] += c0[:, None] * n
        vel[lo:hi] += c1[:, None] * n
        acc[lo:hi] += c2[:, None] * n
    return pos, vel, acc, phi


def add_flats(model, t, s0, delta, ridx, pos=None, vel=None, acc=None):
    """Add the flats of ``model``'s chain (``[chain] roller_flat_by_roller``) to the motion of the stored
    rollers ``ridx`` (0-based), in place: ``pos``, ``vel``, ``acc`` (nt, len(ridx), 2) where given, from
    each roller's undeformed-guide coordinate ``s0`` (nt, len(ridx)) and the tensioner's ``delta`` (nt,)
    at the samples ``t`` (:func:`flat_motion`). Returns the stored rollers that have a flat (1-based)."""
    flats = dict(model.scene.chain.roller_flats)
    done = []
    for q, i in enumerate(np.asarray(ridx, dtype=int)):
        chord = flats.get(int(i) + 1)
        if chord is None:
            continue
        dp, dv, da, _ = flat_motion(model.guide.table, model.guide.p0, t, s0[:, q], delta, float(model.radii[i]), chord)
        for arr, add in ((pos, dp), (vel, dv), (acc, da)):
            if arr is not None:
                arr[:, q] += add
        done.append(int(i) + 1)
    return done
