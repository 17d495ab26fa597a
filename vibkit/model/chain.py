"""Chain closure (the position problem) and its velocity and acceleration recursions.

The chain has p rollers on the guide and p links of pitch L; the last link joins roller p back to
roller 1. Given roller 1's undeformed-guide coordinate ``s0_1`` and a trial tensioner displacement
delta, the chain is *walked* link by link: roller i+1 is the first point of the guide ahead of
roller i at exactly distance L (a closed-form line-circle or circle-circle intersection). One more
step from roller p lands on a "ghost" of roller 1; the chain closes when the ghost falls on roller 1,
``h(delta) = s0_ghost - (s0_1 + P0) = 0``. Newton's method on this scalar equation uses the exact
derivative from the sensitivity recursion below, so each configuration costs O(p) with no p-by-p
solve, and every link but the closing one is exact to rounding by construction.

Velocities. With u_i = r_{i+1} - r_i, the differentiated constraint u_i . (v_{i+1} - v_i) = 0 and
v_i = r_s,i sdot_i + r_d,i deltadot give the affine recursion
``sdot_{i+1} = [u_i.r_s,i sdot_i + u_i.(r_d,i - r_d,{i+1}) deltadot] / (u_i.r_s,{i+1})``,
so sdot_i = alpha_i sdot_1 + beta_i deltadot; the closing link fixes deltadot = c sdot_1, and each
roller velocity is v_i = J_i sdot_1. Accelerations follow from u_i.(a_{i+1} - a_i) + |v_{i+1} - v_i|^2 = 0
the same way: a_i = J_i sddot_1 + h_i. Both satisfy the differentiated constraints to rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from ..runtime.kernel import kernel
from .crossings import crossing_values
from .guide import (
    AX,
    AZ,
    BX,
    BZ,
    COS0,
    CUMD,
    KAPPA,
    LEN0,
    S0,
    SIGP,
    SIN0,
    TRAVEL,
    Guide,
    hit_next,
    local_frame,
    local_inverse,
    local_map,
    locate,
    point_partials,
    seg_length,
)
from .params import ChainParams
from .runs import A_COLS, R_COLS, next_other, nominal_pitch, run_steps
from .slots import PART_XD, PART_XDD, PART_XS, PART_XSD, PART_XSS, PART_ZD, PART_ZDD, PART_ZS, PART_ZSD, PART_ZSS

__all__ = ["Chain", "Configuration", "ClosureError"]


def closure_tolerance(p0: float, n: int) -> float:
    """Smallest meaningful tolerance on the ghost residual of a walk of n links round P0 [m]."""
    return max(1e-13, np.finfo(float).eps * p0 * math.sqrt(n))


class ClosureError(ValueError):
    """The chain cannot close on its guide (too long or too short for the tensioner's travel)."""


# --------------------------------------------------------------------------------------------
# compiled kernels


@kernel()
def walk(tab, p0, s0_1, delta, pitches, n, s0, kk, lam, xs, zs):
    """Walk n links from roller 1 at s0_1 (n+1 points: rollers 1..n and the ghost of roller 1).

    ``pitches[i]`` is the length of the link from roller i+1 to roller i+2 (the last one closes on
    roller 1). Returns the ghost residual h = s0[n] - (s0_1 + P0) [m], or NaN when a link finds no
    guide point at its pitch (delta outside what the guide allows).
    """
    return walk_ghost(tab, p0, s0_1, delta, pitches, n, s0, kk, lam, xs, zs, 1.0)


@kernel()
def walk_ghost(tab, p0, s0_1, delta, pitches, n, s0, kk, lam, xs, zs, runs):
    """:func:`walk`; ``runs`` 0.0 leaves the s0 of a roller after another on a telescopic run at wraps P0 + s0_k (the
    run's inverse map is a tenth of the walk): the same h and points. A float flag: numba compiles a body for each
    bool constant, one for any float. Locals carry the roller before and its segment's constants."""
    wraps = math.floor(s0_1 / p0)
    s = s0_1 - wraps * p0
    k = locate(tab, s)
    lo = local_map(tab, k, s - tab[k, S0], delta)[0]
    qx, qz, _, _ = local_frame(tab, k, lo, delta)
    sq = s0[0] = s0_1
    kk[0], lam[0], xs[0], zs[0] = k, lo, qx, qz
    last_pitch = last_rho = -1.0  # the chord angle on the current arc: recomputed when pitch or radius change
    cd, sd, step = 1.0, 0.0, 0.0
    seg = -1  # the segment whose constants are below
    kap = length = c0 = s0c = rho = cx = cz = 0.0
    for i in range(1, n + 1):
        pitch = pitches[i - 1]
        if k != seg:
            seg, kap, length, c0, s0c = k, tab[k, KAPPA], seg_length(tab, k, delta), tab[k, COS0], tab[k, SIN0]
            if kap != 0.0:
                rho = 1.0 / abs(kap)
                # centre of the arc (it moves with delta only through the segment's start point)
                cx = tab[k, AX] + tab[k, BX] * delta - s0c / kap
                cz = tab[k, AZ] + tab[k, BZ] * delta + c0 / kap
        # the usual case first, in closed form and without trigonometry: the next roller on the
        # same line (one pitch further on) or the same arc (the previous one rotated by the chord angle)
        if kap == 0.0:
            found = lo + pitch
            on = found <= length
            if on:
                if tab[k, SIGP] == 0.0:
                    sq = sq + pitch
                elif runs != 0.0 or i == n:
                    sq = wraps * p0 + tab[k, S0] + local_inverse(tab, k, found, delta)
                else:
                    sq = wraps * p0 + tab[k, S0]  # (not the run's inverse map)
                qx, qz = qx + pitch * c0, qz + pitch * s0c
        else:
            if pitch != last_pitch or rho != last_rho:
                last_pitch, last_rho = pitch, rho
                if pitch < 2.0 * rho:
                    half = math.asin(pitch / (2.0 * rho))
                    step = 2.0 * rho * half
                    cd, sd = math.cos(2.0 * half), math.sin(2.0 * half)
                else:
                    step = math.inf
            found = lo + step
            on = found <= length
            if on:
                rx, rz = qx - cx, qz - cz
                sg = sd if kap > 0.0 else -sd
                sq = sq + step
                qx, qz = cx + cd * rx - sg * rz, cz + sg * rx + cd * rz
        if not on:
            k, found, wraps, _, _ = hit_next(tab, delta, k, qx, qz, pitch, wraps)
            if k < 0:
                return math.nan
            sq = wraps * p0 + tab[k, S0] + (found if tab[k, SIGP] == 0.0 else local_inverse(tab, k, found, delta))
            qx, qz, _, _ = local_frame(tab, k, found, delta)
        lo = found
        kk[i], lam[i], s0[i], xs[i], zs[i] = k, lo, sq, qx, qz
    return sq - (s0_1 + p0)


@kernel()
def fill_partials(tab, p0, s0, kk, lam, delta, m, part):
    """Partial derivatives of r at the first m points of a walk (see guide.point_partials)."""
    for i in range(m):
        k = kk[i]
        s0loc = s0[i] - p0 * math.floor(s0[i] / p0) - tab[k, S0]
        if s0loc < -1e-9:  # point found a hair before its segment's start across the wrap
            s0loc += p0
        point_partials(tab, k, lam[i], s0loc, delta, part[i])


@kernel()
def sensitivity(part, xs, zs, m, alpha, beta):
    """alpha_i = d s0_i / d s0_1 at fixed delta and beta_i = d s0_i / d delta at fixed s0_1."""
    alpha[0] = 1.0
    beta[0] = 0.0
    for i in range(m - 1):
        ux = xs[i + 1] - xs[i]
        uz = zs[i + 1] - zs[i]
        us_i = ux * part[i, PART_XS] + uz * part[i, PART_ZS]
        us_j = ux * part[i + 1, PART_XS] + uz * part[i + 1, PART_ZS]
        ud = ux * (part[i, PART_XD] - part[i + 1, PART_XD]) + uz * (part[i, PART_ZD] - part[i + 1, PART_ZD])
        alpha[i + 1] = us_i * alpha[i] / us_j
        beta[i + 1] = (us_i * beta[i] + ud) / us_j


@kernel()
def solve_closure(tab, p0, lt, s0_1, delta0, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol):
    """Newton's method on the ghost residual h(delta), safeguarded by bisection.

    Returns (delta, iterations, status): status 0 converged, 2 iteration limit (the walk failing at
    every trial delta ends there too).
    """
    lo, hi = -lt * TRAVEL * (1.0 - 1e-9), lt * TRAVEL * (1.0 - 1e-9)
    have_lo, have_hi = False, False
    d = delta0
    for it in range(100):
        h = walk(tab, p0, s0_1, d, pitches, n, s0, kk, lam, xs, zs)
        if math.isnan(h):
            # the walk found no guide point at a link's pitch: delta is off the feasible range;
            # retreat towards the known side of the bracket, or towards the middle of the travel
            if have_lo and have_hi:
                d = 0.5 * (lo + hi)
            elif have_lo:
                d = 0.5 * (d + lo)
            elif have_hi:
                d = 0.5 * (d + hi)
            else:
                d = 0.5 * d
            continue
        if abs(h) <= tol:
            return d, it, 0
        if h < 0.0:
            lo, have_lo = d, True
        else:
            hi, have_hi = d, True
        fill_partials(tab, p0, s0, kk, lam, d, n + 1, part)
        sensitivity(part, xs, zs, n + 1, alpha, beta)
        dh = beta[n]
        step = -h / dh if dh != 0.0 else 0.0
        dn = d + step
        # Newton can cycle where the ghost roller sits on a curvature joint (h is only C1 there):
        # after a few iterations every other step bisects the bracket, which always converges
        if it >= 6 and have_lo and have_hi and it % 2 == 0:
            dn = 0.5 * (lo + hi)
        elif not (dn > lo and dn < hi) or dh <= 0.0:
            if have_lo and have_hi:
                dn = 0.5 * (lo + hi)
            elif h < 0.0:
                dn = 0.5 * (d + hi)
            else:
                dn = 0.5 * (d + lo)
        # stalled at the resolution of delta: rounding in a long walk keeps |h| just above tol
        if abs(dn - d) <= 8.0 * 2.220446049250313e-16 * max(abs(d), 1e-3):
            return dn, it, 0 if abs(h) < 1e3 * tol else 2
        d = dn
    return d, 100, 2


CHORD_WALKS = 3  # walks along chord steps before a full Newton solve takes over


@kernel()
def close_with_slope(tab, p0, lt, s0_1, guess, slope, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol):
    """Close the chain from a predicted delta with a known dh/ddelta ``slope`` (a chord-Newton step,
    no partial derivatives), as many evaluations along a trajectory can; falls back to
    :func:`solve_closure` when that does not meet the tolerance (or ``slope`` is not positive).

    Returns (delta, walks, status). The test for convergence is the same, |h| <= tol, so the result
    is as accurate as solve_closure's.
    """
    walks = 0
    if slope > 0.0:
        # chord steps converge linearly, at the rate of the slope's relative change since it was taken
        for _ in range(CHORD_WALKS):
            h = walk(tab, p0, s0_1, guess, pitches, n, s0, kk, lam, xs, zs)
            walks += 1
            if math.isnan(h):
                break
            if abs(h) <= tol:
                return guess, walks, 0
            guess = guess - h / slope
    d, it, st = solve_closure(tab, p0, lt, s0_1, guess, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol)
    return d, walks + it + 1, st


@kernel()
def closure_residual(xs, zs, n, pitches):
    """max over the n links (the last one closing on roller 1) of | |r_{i+1} - r_i| - L_i |. [m]"""
    worst = 0.0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        d = abs(math.hypot(xs[j] - xs[i], zs[j] - zs[i]) - pitches[i])
        if d > worst:
            worst = d
    return worst


@kernel()
def velocity_coefficients(part, xs, zs, n, alpha, beta, jac, gam):
    """c = d delta/d s0_1, gamma_i = d s0_i/d s0_1 and J_i = d r_i/d s0_1 (fills jac (n,2), gam (n,)).

    Expects alpha, beta from ``sensitivity`` over the n rollers; the closing link joins roller n to 1.
    """
    ux = xs[0] - xs[n - 1]
    uz = zs[0] - zs[n - 1]
    ur1 = ux * part[0, PART_XS] + uz * part[0, PART_ZS]
    urp = ux * part[n - 1, PART_XS] + uz * part[n - 1, PART_ZS]
    ud = ux * (part[0, PART_XD] - part[n - 1, PART_XD]) + uz * (part[0, PART_ZD] - part[n - 1, PART_ZD])
    den = ud - urp * beta[n - 1]
    c = (urp * alpha[n - 1] - ur1) / den
    for i in range(n):
        g = alpha[i] + beta[i] * c
        gam[i] = g
        jac[i, 0] = part[i, PART_XS] * g + part[i, PART_XD] * c
        jac[i, 1] = part[i, PART_ZS] * g + part[i, PART_ZD] * c
    return c


@kernel()
def acceleration_terms(part, xs, zs, n, alpha, beta, gam, c, sdot1, hacc, eta, sd):
    """Velocity-dependent acceleration h_i (fills hacc (n,2)) and e, with
    a_i = J_i sddot_1 + h_i and deltaddot = c sddot_1 + e, at roller-1 speed sdot1 [m/s]."""
    ddot = c * sdot1
    # w_i = r_ss sdot^2 + 2 r_sd sdot ddot + r_dd ddot^2, stored temporarily in hacc
    for i in range(n):
        s = gam[i] * sdot1
        sd[i] = s
        hacc[i, 0] = part[i, PART_XSS] * s * s + 2.0 * part[i, PART_XSD] * s * ddot + part[i, PART_XDD] * ddot * ddot
        hacc[i, 1] = part[i, PART_ZSS] * s * s + 2.0 * part[i, PART_ZSD] * s * ddot + part[i, PART_ZDD] * ddot * ddot
    eta[0] = 0.0
    for i in range(n - 1):
        ux = xs[i + 1] - xs[i]
        uz = zs[i + 1] - zs[i]
        dvx = (part[i + 1, PART_XS] * sd[i + 1] + part[i + 1, PART_XD] * ddot) - (
            part[i, PART_XS] * sd[i] + part[i, PART_XD] * ddot
        )
        dvz = (part[i + 1, PART_ZS] * sd[i + 1] + part[i + 1, PART_ZD] * ddot) - (
            part[i, PART_ZS] * sd[i] + part[i, PART_ZD] * ddot
        )
        us_i = ux * part[i, PART_XS] + uz * part[i, PART_ZS]
        us_j = ux * part[i + 1, PART_XS] + uz * part[i + 1, PART_ZS]
        uw = ux * (hacc[i, 0] - hacc[i + 1, 0]) + uz * (hacc[i, 1] - hacc[i + 1, 1])
        eta[i + 1] = (us_i * eta[i] + uw - (dvx * dvx + dvz * dvz)) / us_j
    p = n - 1
    ux = xs[0] - xs[p]
    uz = zs[0] - zs[p]
    dvx = (part[0, PART_XS] * sd[0] + part[0, PART_XD] * ddot) - (part[p, PART_XS] * sd[p] + part[p, PART_XD] * ddot)
    dvz = (part[0, PART_ZS] * sd[0] + part[0, PART_ZD] * ddot) - (part[p, PART_ZS] * sd[p] + part[p, PART_ZD] * ddot)
    urp = ux * part[p, PART_XS] + uz * part[p, PART_ZS]
    ud = ux * (part[0, PART_XD] - part[p, PART_XD]) + uz * (part[0, PART_ZD] - part[p, PART_ZD])
    den = ud - urp * beta[p]
    kk = ux * (hacc[0, 0] - hacc[p, 0]) + uz * (hacc[0, 1] - hacc[p, 1]) - urp * eta[p] + dvx * dvx + dvz * dvz
    e = -kk / den
    for i in range(n):
        t = beta[i] * e + eta[i]
        hacc[i, 0] += part[i, PART_XS] * t + part[i, PART_XD] * e
        hacc[i, 1] += part[i, PART_ZS] * t + part[i, PART_ZD] * e
    return e


@nb.njit(cache=True, error_model="numpy")
def walk_arrays(n):
    """Scratch arrays of a walk of n links and its sensitivities: s0, segment, local coordinate,
    x, z (n + 1 each), partials (n + 1, 12), alpha, beta (n + 1 each)."""
    return (
        np.empty(n + 1),
        np.empty(n + 1, dtype=np.int64),
        np.empty(n + 1),
        np.empty(n + 1),
        np.empty(n + 1),
        np.empty((n + 1, 12)),
        np.empty(n + 1),
        np.empty(n + 1),
    )


@nb.njit(cache=True, error_model="numpy")
def sweep_kernel(tab, p0, lt, s0_values, delta0, pitches, n, tol, deltas, resid, status):
    """Kinematic sweep: closure at every s0_1 in ``s0_values``.

    Along a fine sweep delta is smooth almost everywhere, so each configuration starts from the
    linear extrapolation of the last two and takes one chord-Newton step with the last exact
    derivative dh/ddelta: two walks and no partial derivatives. Whenever that does not meet the
    tolerance (a curvature joint, a coarse step) the full safeguarded Newton takes over and
    refreshes the derivative.
    """
    s0, kk, lam, xs, zs, part, alpha, beta = walk_arrays(n)
    d = delta0
    d_prev = delta0
    slope = 0.0  # dh/ddelta from the last full Newton solve; 0 = unknown
    for j in range(s0_values.size):
        guess = 2.0 * d - d_prev if j >= 2 else d
        done = False
        if slope > 0.0:
            h = walk(tab, p0, s0_values[j], guess, pitches, n, s0, kk, lam, xs, zs)
            if not math.isnan(h):
                if abs(h) <= tol:
                    done = True
                    dn = guess
                else:
                    dn = guess - h / slope
                    h = walk(tab, p0, s0_values[j], dn, pitches, n, s0, kk, lam, xs, zs)
                    done = (not math.isnan(h)) and abs(h) <= tol
        if not done:
            dn, _, st = solve_closure(
                tab, p0, lt, s0_values[j], guess, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol
            )
            status[j] = st
            if st != 0:
                deltas[j] = dn
                return j
            slope = beta[n]
        else:
            status[j] = 0
        d_prev = d
        d = dn
        deltas[j] = d
        resid[j] = closure_residual(xs, zs, n, pitches)
    return s0_values.size


# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Configuration:
    """One closed configuration of the chain.

    Attributes
    ----------
    s0 : ndarray (p,)
        Undeformed-guide coordinate of each roller (unwrapped, increasing). [m]
    position : ndarray (p, 2)
        Roller centres (x, z). [m]
    delta : float
        Tensioner displacement. [m]
    segment : ndarray (p,)
        Index (0-13) of the guide segment holding each roller.
    closure_residual : float
        max over links of | |r_{i+1} - r_i| - L |. [m]
    """

    s0: np.ndarray
    position: np.ndarray
    delta: float
    segment: np.ndarray
    closure_residual: float
    lam: np.ndarray
    partials: np.ndarray


class Chain:
    """A closed roller chain on a guide: closure, velocities and accelerations.

    Parameters
    ----------
    guide : Guide
    chain : ChainParams
    tol : float
        Tolerance on the closing link's ghost residual. [m]
    """

    def __init__(self, guide: Guide, chain: ChainParams, *, tol: float = 1e-13):
        self.guide = guide
        self.params = chain
        self.n = chain.n_rollers
        self.pitch = chain.link_pitch
        self.pitches = chain.pitches()
        # a walk of p links accumulates rounding of about eps * P0 * sqrt(p): the tolerance on the
        # ghost residual never asks for less (it is 1e-13 m up to a few hundred rollers)
        self.tol = max(tol, closure_tolerance(guide.p0, chain.n_rollers))
        self._lt = guide.params.tensioner_length
        n = self.n
        self._s0 = np.empty(n + 1)
        self._kk = np.empty(n + 1, dtype=np.int64)
        self._lam = np.empty(n + 1)
        self._xs = np.empty(n + 1)
        self._zs = np.empty(n + 1)
        self._part = np.empty((n + 1, 12))
        self._alpha = np.empty(n + 1)
        self._beta = np.empty(n + 1)
        self._delta_guess = None

    # -- position problem -------------------------------------------------------------------
    def find_delta_bracket(self, s0_1: float) -> float:
        """A starting delta for s0_1 found by scanning the tensioner's travel; raises ClosureError."""
        lt = self._lt * TRAVEL
        grid = np.linspace(-lt, lt, 81)[1:-1]
        hs = np.array(
            [
                walk(
                    self.guide.table,
                    self.guide.p0,
                    s0_1,
                    d,
                    self.pitches,
                    self.n,
                    self._s0,
                    self._kk,
                    self._lam,
                    self._xs,
                    self._zs,
                )
                for d in grid
            ]
        )
        ok = np.isfinite(hs)
        sign_change = np.nonzero(ok[:-1] & ok[1:] & (np.sign(hs[:-1]) != np.sign(hs[1:])))[0]
        if sign_change.size == 0:
            length = float(self.pitches.sum())
            raise ClosureError(
                f"a chain of {self.n} links of pitch {self.pitch:.6g} m ({length:.6g} m) cannot close on this guide: "
                f"its perimeter is {self.guide.p0:.6g} m less 2*delta, with delta within the tensioner travel "
                f"(-{lt:.6g}, {lt:.6g}) m; check the number of links (a profile's chain.n_links, a scene's "
                "chain.n_rollers) and the guide's length (geometry.rise, guide.incline_length)"
            )
        i = sign_change[0]
        return float(0.5 * (grid[i] + grid[i + 1]))

    def _no_closure(self, s0_1: float) -> str:
        """What to change when the chain could not be closed with roller 1 at ``s0_1`` [m] (not the solver's
        state: the chain's length against the loop and the tensioner's travel)."""
        length = float(self.pitches.sum())
        slack = (self.guide.p0 - length) / 2.0
        return (
            f"the chain of {self.n} links ({length:.4g} m) does not close on its guide ({self.guide.p0:.4g} m round) "
            f"with roller 1 {s0_1:.3g} m round the loop: the tensioner would have to move about {1000 * slack:.0f} mm "
            f"of its +-{1000 * self._lt * TRAVEL:.0f} mm travel; check the number of links (a profile's "
            "chain.n_links, a scene's chain.n_rollers) and the guide's length (geometry.rise, guide.incline_length)"
        )

    def configure(self, s0_1: float, delta_guess: float | None = None) -> Configuration:
        """Close the chain with roller 1 at undeformed-guide coordinate s0_1 [m]."""
        g = self.guide
        guess = delta_guess if delta_guess is not None else self._delta_guess
        if guess is None:
            guess = self.find_delta_bracket(s0_1)
        d, _, st = solve_closure(
            g.table,
            g.p0,
            self._lt,
            float(s0_1),
            float(guess),
            self.pitches,
            self.n,
            self._s0,
            self._kk,
            self._lam,
            self._xs,
            self._zs,
            self._part,
            self._alpha,
            self._beta,
            self.tol,
        )
        if st != 0:
            guess = self.find_delta_bracket(s0_1)
            d, _, st = solve_closure(
                g.table,
                g.p0,
                self._lt,
                float(s0_1),
                guess,
                self.pitches,
                self.n,
                self._s0,
                self._kk,
                self._lam,
                self._xs,
                self._zs,
                self._part,
                self._alpha,
                self._beta,
                self.tol,
            )
            if st != 0:
                raise ClosureError(self._no_closure(s0_1))
        self._delta_guess = d
        n = self.n
        fill_partials(g.table, g.p0, self._s0, self._kk, self._lam, d, n, self._part)
        return Configuration(
            s0=self._s0[:n].copy(),
            position=np.column_stack([self._xs[:n], self._zs[:n]]),
            delta=float(d),
            segment=self._kk[:n].copy(),
            closure_residual=float(closure_residual(self._xs, self._zs, n, self.pitches)),
            lam=self._lam[:n].copy(),
            partials=self._part[:n].copy(),
        )

    # -- velocities and accelerations -------------------------------------------------------
    def jacobian(self, conf: Configuration):
        """J (p, 2) = d r_i / d s0_1, gamma (p,) = d s0_i / d s0_1, c = d delta / d s0_1, and alpha, beta."""
        n = self.n
        alpha, beta = np.empty(n), np.empty(n)
        xs, zs = conf.position[:, 0].copy(), conf.position[:, 1].copy()
        sensitivity(conf.partials, xs, zs, n, alpha, beta)
        jac, gam = np.empty((n, 2)), np.empty(n)
        c = velocity_coefficients(conf.partials, xs, zs, n, alpha, beta, jac, gam)
        return jac, gam, float(c), alpha, beta

    def motion(self, conf: Configuration, s0dot_1: float, s0ddot_1: float):
        """Roller velocities and accelerations for roller-1 rates s0dot_1 [m/s], s0ddot_1 [m/s^2].

        Returns a dict with ``velocity`` (p,2), ``acceleration`` (p,2), ``s0dot`` (p,), ``delta_dot``,
        ``delta_ddot``, ``jacobian`` (p,2), ``h`` (p,2), ``c``, ``e``.
        """
        n = self.n
        jac, gam, c, alpha, beta = self.jacobian(conf)
        xs, zs = conf.position[:, 0].copy(), conf.position[:, 1].copy()
        hacc, eta, sd = np.empty((n, 2)), np.empty(n), np.empty(n)
        e = acceleration_terms(conf.partials, xs, zs, n, alpha, beta, gam, c, float(s0dot_1), hacc, eta, sd)
        return {
            "velocity": jac * s0dot_1,
            "acceleration": jac * s0ddot_1 + hacc,
            "s0dot": gam * s0dot_1,
            "delta_dot": c * s0dot_1,
            "delta_ddot": c * s0ddot_1 + e,
            "jacobian": jac,
            "h": hacc,
            "c": c,
            "e": float(e),
        }

    # -- where the rollers cross the guide's breakpoints ------------------------------------
    def crossing_table(self, breakpoints: np.ndarray | None = None, rollers_at=()) -> np.ndarray:
        """Values of s0_1 in [0, P0) at which some roller sits on a breakpoint of the guide. [m]

        The configuration is a function of s0_1 alone, so the instants at which a roller crosses a
        curvature jump are the instants at which s0_1 crosses one of these values. With equal
        pitches the chain with roller 1 on breakpoint b is the chain with roller j on it, relabelled:
        the values for breakpoint b are the s0 of every roller in that one configuration. With
        per-link pitches each value is refined by Newton's method from there.

        ``rollers_at`` adds, for pairs (roller index from 0, place s0 [m]), the values of s0_1 at
        which that roller passes that place (where a passenger boards or alights).
        """
        p0 = self.guide.p0
        n = self.n
        bps = self.guide.breakpoints() if breakpoints is None else np.asarray(breakpoints, dtype=float)
        uniform = bool(np.all(self.pitches == self.pitches[0]))
        out = []
        rollers, places, starts = [], [], []  # with unequal links: each pair refined by Newton's method
        for b in bps:
            vals = np.mod(self.configure(float(b)).s0, p0)
            if uniform:
                out.append(vals)
            else:
                # with roller 1 at vals[j] it is roller (n - j) mod n that sits on b
                rollers.append((n - np.arange(n)) % n)
                places.append(np.full(n, float(b)))
                starts.append(vals)
        for k, place in rollers_at:
            vals = np.mod(self.configure(float(place)).s0, p0)
            rollers.append([int(k)])
            places.append([float(place)])
            starts.append([float(vals[(n - int(k)) % n])])
        if rollers:
            out.append(self._crossings(np.concatenate(rollers), np.concatenate(places), np.concatenate(starts)))
        tab = np.unique(np.mod(np.concatenate(out), p0))
        # rollers that cross breakpoints together (the guide's symmetries) give one value
        keep = np.concatenate([[True], np.diff(tab) > 1e-12 * p0])
        return np.ascontiguousarray(tab[keep])

    def _crossings(self, rollers, places, starts):
        """s0_1 near each of ``starts`` at which roller ``rollers[i]`` (from 0) sits at undeformed
        coordinate ``places[i]`` (:func:`vibkit.model.crossings.crossing_values`). [m]"""
        g = self.guide
        out = np.empty(len(starts))
        guess = self._delta_guess if self._delta_guess is not None else self.find_delta_bracket(float(starts[0]))
        nominal = nominal_pitch(self.pitches)
        bad = crossing_values(
            g.table,
            g.p0,
            self.pitches,
            self.n,
            self.tol,
            run_steps(g.table, nominal, self.n),
            next_other(self.pitches, nominal),
            np.zeros((self.n + 2, R_COLS)),
            np.zeros(A_COLS),
            np.ascontiguousarray(rollers, dtype=np.int64),
            np.ascontiguousarray(places, dtype=float),
            np.ascontiguousarray(starts, dtype=float),
            float(guess),
            out,
        )
        if bad >= 0:
            raise ClosureError(self._no_closure(starts[bad]))
        return out

    # -- sweep ------------------------------------------------------------------------------
    def sweep(self, s0_values: np.ndarray, delta_guess: float | None = None):
        """delta and closure residual at each s0_1 in s0_values (one compiled loop). [m]"""
        s0_values = np.ascontiguousarray(s0_values, dtype=float)
        guess = delta_guess if delta_guess is not None else self.find_delta_bracket(float(s0_values[0]))
        deltas = np.empty(s0_values.size)
        resid = np.empty(s0_values.size)
        status = np.zeros(s0_values.size, dtype=np.int64)
        g = self.guide
        done = sweep_kernel(
            g.table, g.p0, self._lt, s0_values, guess, self.pitches, self.n, self.tol, deltas, resid, status
        )
        if done < s0_values.size:
            raise ClosureError(
                f"chain closure failed at s0_1 = {s0_values[done]:.9g} m (status {status[done]}) during the sweep"
            )
        return deltas, resid

    def s_deformed(self, s0: float, delta: float):
        """Deformed arc length s of a point at s0 (one loop), with ds/ds0, ds/ddelta, d2s/ds0^2 and
        d2s/ds0 ddelta there."""
        tab, p0 = self.guide.table, self.guide.p0
        s0w = s0 - p0 * math.floor(s0 / p0)
        k = locate(tab, s0w)
        lam, ls, ld, lss, lsd = local_map(tab, k, s0w - tab[k, S0], delta)
        return tab[k, S0] + tab[k, CUMD] * delta + lam, ls, tab[k, CUMD] + ld, lss, lsd


def segment_length_table(guide: Guide) -> np.ndarray:
    """Undeformed segment lengths (for reports). [m]"""
    return guide.table[:, LEN0].copy()
