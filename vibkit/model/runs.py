"""The chain closed run by run: the exact closure at a cost that grows with the guide's segments.

Between two *joints* (a link that crosses from one segment of the guide to the next, or a link of
another pitch than its neighbours) the rollers form a *run* of equal links on one segment: on a line
each is one pitch further on, on an arc each is the previous one turned by the chord angle, and the
segment itself moves, if at all, rigidly with delta (:mod:`vibkit.model.guide`: r = A_k + B_k delta +
f_k(lam)). So a run moves as one body: every roller of it has the same rate of local arc length,
lam-dot = alpha s-dot + beta delta-dot, and the same lam-ddot = alpha s-ddot + beta delta-ddot + q.

A walk (:func:`run_walk`) visits joints only: the end of a run in closed form (how many links fit on
the segment, and the last roller's place), one exact link over each joint (the same
:func:`vibkit.model.guide.circle_hit` as :func:`vibkit.model.chain.walk`), and the rates carried across
the joint by the link's constraint, u . (v_B - v_A) = 0. The ghost of roller 1 (model.md section 3)
gives the residual h and, from the same rates, dh/ddelta for Newton's method. With the rates' closure
(the ghost's s0-dot is roller 1's) fixing c = ddelta/ds and the accelerations'
(``u . (a_B - a_A) + |v_B - v_A|^2 = 0`` across each joint) fixing e (delta-ddot = c s-ddot + e), :func:`run_fill` writes
every roller's place, J = dr/ds and h (a = J s-ddot + h) into the work arrays that
:func:`vibkit.model.effects.evaluate_forces` takes from there.

Nothing is tabulated or approximated: this is the exact closure, walked in about 20 joints instead
of 160 links, for any chain (worn links, rollers of their own mass or radius, passengers, rolling
resistance). ``tests/model/test_runs.py`` compares it with :func:`vibkit.model.effects.evaluate`.
"""

from __future__ import annotations

import math

import numpy as np

from ..runtime.kernel import kernel
from .guide import (
    AX,
    AZ,
    BX,
    BZ,
    COS0,
    KAPPA,
    LEN0,
    RAMP,
    S0,
    SIGP,
    SIN0,
    hit_next,
    local_frame,
    local_inverse,
    local_map,
    locate,
    seg_length,
)

__all__ = [
    "RS_COS",
    "RS_NEAR",
    "RS_SIN",
    "RS_SIN_HALF",
    "RS_STEP",
    "TURNS",
    "next_other",
    "nominal_pitch",
    "roller_s0",
    "run_close",
    "run_fill",
    "run_rates",
    "run_roller",
    "run_steps",
    "run_walk",
]

# columns of a run's record (one row per run, in walking order)
R_SEG, R_FIRST, R_LAST, R_LAM, R_WRAPS = 0, 1, 2, 3, 4
R_X, R_Z, R_TX, R_TZ = 5, 6, 7, 8  # the run's first roller: place and unit tangent
R_ALPHA, R_BETA, R_Q = 9, 10, 11  # lam-dot = alpha s-dot + beta delta-dot; q: lam-ddot's constant
R_XE, R_ZE, R_TXE, R_TZE = 12, 13, 14, 15  # the run's last roller
R_STEP = 16  # the arc length of one link along the segment [m]
R_COLS = 17
# the auxiliary slots: local_map's partials at roller 1 and at the ghost, the runs walked
A_ONE, A_GHOST, A_RUNS, A_DEP = 0, 4, 8, 9
A_COLS = 10

MAX_NEWTON = 30
# columns of run_steps' table: one link's arc length along the segment, the cosine and sine of its turn,
# whether the segment comes within the sprocket's reach (set by runs_rhs.build_runs), the sine of half the
# turn; from TURNS on, the cosine and sine of m half-turns side by side
RS_STEP, RS_COS, RS_SIN, RS_NEAR, RS_SIN_HALF, TURNS = 0, 1, 2, 3, 4, 5


def nominal_pitch(pitches):
    """The pitch most links have (the one runs are made of). [m]"""
    values, counts = np.unique(pitches, return_counts=True)
    return float(values[np.argmax(counts)])


def run_steps(tab, pitch, n):
    """Per segment: the arc length one link of ``pitch`` spans along it, and the cosine and sine of
    the angle it turns on an arc, 0 (the column :func:`vibkit.model.runs_rhs.build_runs` marks segments
    within the sprocket's reach in) and the sine of half the angle (inf where the link is longer than
    the arc's diameter); then, from column ``TURNS``, the cosine and sine of m half-angles for m = 0 ..
    2 n + 2 side by side (a run of m links on an arc turns by 2 m of them: no trigonometry in a walk
    or a run's sums). (nseg, TURNS + 4 n + 6)"""
    out = np.zeros((tab.shape[0], TURNS + 2 * (2 * n + 3)))
    m = np.arange(2 * n + 3)
    for k in range(tab.shape[0]):
        kap = tab[k, KAPPA]
        out[k, TURNS::2] = 1.0
        if kap == 0.0:
            out[k, :5] = (pitch, 1.0, 0.0, 0.0, 0.0)
            continue
        rho = 1.0 / abs(kap)
        if pitch >= 2.0 * rho:
            out[k, :5] = (math.inf, 1.0, 0.0, 0.0, 0.0)
            continue
        step = 2.0 * rho * math.asin(pitch / (2.0 * rho))
        half = 0.5 * kap * step
        out[k, :5] = (step, math.cos(kap * step), math.sin(kap * step), 0.0, math.sin(half))
        out[k, TURNS::2] = np.cos(m * half)
        out[k, TURNS + 1 :: 2] = np.sin(m * half)
    return out


def next_other(pitches, nominal):
    """For each roller i in 0..n: the first r >= i whose link (to roller r + 1) is not of the nominal
    pitch, or n. (n + 1,) int64"""
    n = pitches.size
    out = np.full(n + 1, n, dtype=np.int64)
    nxt = n
    for r in range(n - 1, -1, -1):
        if pitches[r] != nominal:
            nxt = r
        out[r] = nxt
    return out


@kernel()
def _link(tab, delta, k, lo, qx, qz, pitch, wraps, within):
    """One link of ``pitch`` from the roller on segment k at local arc length lo, place (qx, qz):
    the next roller's (segment, lam, x, z, tx, tz, wraps), segment -1 where the guide has no point at
    that distance. The same construction as :func:`vibkit.model.chain.walk`; ``within`` False skips
    the try on segment k (the caller knows the link does not end on it)."""
    if within:
        kap = tab[k, KAPPA]
        length = seg_length(tab, k, delta)
        if kap == 0.0:
            found = lo + pitch
            if found <= length:
                c0, s0 = tab[k, COS0], tab[k, SIN0]
                return k, found, qx + pitch * c0, qz + pitch * s0, c0, s0, wraps
        else:
            rho = 1.0 / abs(kap)
            if pitch < 2.0 * rho:
                found = lo + 2.0 * rho * math.asin(pitch / (2.0 * rho))
                if found <= length:
                    x, z, tx, tz = local_frame(tab, k, found, delta)
                    return k, found, x, z, tx, tz, wraps
    k, found, wraps, x, z = hit_next(tab, delta, k, qx, qz, pitch, wraps)
    if k < 0:
        return -1, 0.0, 0.0, 0.0, 0.0, 0.0, wraps
    kap = tab[k, KAPPA]
    if kap == 0.0:
        return k, found, x, z, tab[k, COS0], tab[k, SIN0], wraps
    # on an arc the tangent is the radius turned a quarter: (x, z) = centre + (sin phi, -cos phi) / kappa
    cx = tab[k, AX] + tab[k, BX] * delta - tab[k, SIN0] / kap
    cz = tab[k, AZ] + tab[k, BZ] * delta + tab[k, COS0] / kap
    return k, found, x, z, -(z - cz) * kap, (x - cx) * kap, wraps


@kernel(inline="always")
def _inverse(tab, k, lam, delta):
    """s0 - s0_k at local arc length lam on segment k: closed form on a telescopic run's straight
    middle (where the map is linear), else :func:`vibkit.model.guide.local_inverse`."""
    if tab[k, SIGP] != 0.0:
        lt = tab[k, LEN0]
        a = 1.0 / (1.0 - RAMP)
        x = (lam - 0.5 * delta * a * RAMP) / (1.0 - delta * a / lt)
        if RAMP * lt < x < (1.0 - RAMP) * lt:
            return x
    return local_inverse(tab, k, lam, delta)


@kernel(inline="always")
def roller_s0(tab, p0, k, lam, wraps, delta):
    """s0 of a roller on segment k at local arc length lam, ``wraps`` loops on. [m]"""
    return wraps * p0 + tab[k, S0] + _inverse(tab, k, lam, delta)


@kernel(inline="always")
def _moving(tab, k):
    """Whether segment k moves or stretches with delta."""
    return tab[k, BX] != 0.0 or tab[k, BZ] != 0.0 or tab[k, SIGP] != 0.0


@kernel()
def run_walk(tab, p0, s, delta, pitches, n, rstep, rnext, runs, aux, resume):
    """Walk the chain from roller 1 at s0 = s at trial ``delta``, run by run (see the module
    docstring), recording each run in ``runs`` with its rate coefficients. Returns (h, dh/ddelta):
    the ghost's residual s0_ghost - (s + P0) and its derivative; h is NaN where a link finds no guide
    point. ``aux`` receives local_map's partials at roller 1 and at the ghost, the number of runs and
    the first run on a segment that moves with delta. With ``resume`` > 0 the walk keeps the runs
    before that one (of an earlier walk at the same s, none of which moves with delta) and walks on
    from there."""
    if resume > 0:
        pr = resume - 1
        k, i, wraps = int(runs[pr, R_SEG]), int(runs[pr, R_LAST]), runs[pr, R_WRAPS]
        lam = runs[pr, R_LAM] + (runs[pr, R_LAST] - runs[pr, R_FIRST]) * runs[pr, R_STEP]
        x, z, tx, tz = runs[pr, R_XE], runs[pr, R_ZE], runs[pr, R_TXE], runs[pr, R_TZE]
        al, be = runs[pr, R_ALPHA], runs[pr, R_BETA]
        r = resume
        dep = resume
    else:
        wraps = math.floor(s / p0)
        sl = s - wraps * p0
        k = locate(tab, sl)
        lam, ls, ld, lss, lsd = local_map(tab, k, sl - tab[k, S0], delta)
        aux[A_ONE], aux[A_ONE + 1], aux[A_ONE + 2], aux[A_ONE + 3] = ls, ld, lss, lsd
        x, z, tx, tz = local_frame(tab, k, lam, delta)
        al, be = ls, ld
        i = 0
        r = 0
        dep = -1
    link = resume > 0
    within = True
    while True:
        if link:
            kn, ln, xn, zn, txn, tzn, wraps = _link(tab, delta, k, lam, x, z, pitches[i], wraps, within)
            if kn < 0:
                aux[A_RUNS] = r
                return math.nan, 0.0
            # the rates across the joint: u . (v_B - v_A) = 0 with v = B_k delta-dot + T lam-dot
            ux, uz = xn - x, zn - z
            uta = ux * tx + uz * tz
            utb = ux * txn + uz * tzn
            uba = ux * tab[k, BX] + uz * tab[k, BZ]
            ubb = ux * tab[kn, BX] + uz * tab[kn, BZ]
            al = uta * al / utb
            be = (uba + uta * be - ubb) / utb
            k, lam, x, z, tx, tz = kn, ln, xn, zn, txn, tzn
            i += 1
        link = True
        if dep < 0 and _moving(tab, k):
            dep = r
        step = rstep[k, RS_STEP]
        m = 0
        room = seg_length(tab, k, delta) - lam
        cap = min(rnext[i], n) - i
        if room >= step:
            m = int(room / step)
            if m > cap:
                m = cap
        # the next link is tried on this segment unless it is of the run's pitch and found no room
        within = m == cap or room >= (m + 1) * step
        runs[r, R_SEG] = k
        runs[r, R_FIRST] = i
        runs[r, R_LAST] = i + m
        runs[r, R_LAM] = lam
        runs[r, R_WRAPS] = wraps
        runs[r, R_X] = x
        runs[r, R_Z] = z
        runs[r, R_TX] = tx
        runs[r, R_TZ] = tz
        runs[r, R_ALPHA] = al
        runs[r, R_BETA] = be
        runs[r, R_STEP] = step
        if m > 0:
            lam += m * step
            kap = tab[k, KAPPA]
            if kap == 0.0:
                x, z, tx, tz = local_frame(tab, k, lam, delta)
            else:
                # the first roller's tangent turned by the m links' 2 m half-angles, about the arc's centre
                cx, cz = x - tz / kap, z + tx / kap
                ct, st = rstep[k, TURNS + 4 * m], rstep[k, TURNS + 4 * m + 1]
                tx, tz = tx * ct - tz * st, tz * ct + tx * st
                x, z = cx + tz / kap, cz - tx / kap
        runs[r, R_XE] = x
        runs[r, R_ZE] = z
        runs[r, R_TXE] = tx
        runs[r, R_TZE] = tz
        r += 1
        i += m
        if i == n:
            break
    aux[A_RUNS] = r
    aux[A_DEP] = dep
    # the ghost (roller n) is the last run's last roller
    s0loc = _inverse(tab, k, lam, delta)
    _, lsg, ldg, lssg, lsdg = local_map(tab, k, s0loc, delta)
    aux[A_GHOST], aux[A_GHOST + 1], aux[A_GHOST + 2], aux[A_GHOST + 3] = lsg, ldg, lssg, lsdg
    h = wraps * p0 + tab[k, S0] + s0loc - (s + p0)
    return h, (be - ldg) / lsg


@kernel()
def run_close(tab, p0, s, guess, pitches, n, tol, rstep, rnext, runs, aux):
    """Newton's method on delta from ``guess`` with the walk's own dh/ddelta; after the first walk
    only the runs from the first segment that moves with delta are walked again. Returns (delta,
    walks, status): status 0 closed to ``tol``, 1 not (the caller falls back to the safeguarded
    exact closure)."""
    d = guess
    resume = 0
    for it in range(MAX_NEWTON):
        h, dh = run_walk(tab, p0, s, d, pitches, n, rstep, rnext, runs, aux, resume)
        if math.isnan(h) or not dh > 0.0:
            return d, it + 1, 1
        if abs(h) <= tol:
            return d, it + 1, 0
        dn = d - h / dh
        if abs(dn - d) <= 8.0 * 2.220446049250313e-16 * max(abs(d), 1e-3):
            # stalled at the resolution of delta; the walk is the one at d
            return d, it + 1, 0 if abs(h) < 1e3 * tol else 1
        d = dn
        resume = max(int(aux[A_DEP]), 0)
    return d, MAX_NEWTON, 1


@kernel()
def run_rates(tab, sdot, runs, aux):
    """From the closed walk: c = ddelta/ds, e (delta-ddot = c s-ddot + e) and each run's q (its
    lam-ddot = alpha s-ddot + beta delta-ddot + q) at roller-1 speed ``sdot``. Returns (c, e, dh/ddelta)."""
    nr = int(aux[A_RUNS])
    g = nr - 1
    lsg, ldg = aux[A_GHOST], aux[A_GHOST + 1]
    c = (lsg - runs[g, R_ALPHA]) / (runs[g, R_BETA] - ldg)
    sd2 = sdot * sdot
    ddot = c * sdot
    # lam-ddot's constant q, run by run: u . (a_B - a_A) + |v_B - v_A|^2 = 0 across each joint
    q = (aux[A_ONE + 2] + 2.0 * aux[A_ONE + 3] * c) * sd2
    runs[0, R_Q] = q
    for r in range(1, nr):
        a, b = r - 1, r
        ka, kb = int(runs[a, R_SEG]), int(runs[b, R_SEG])
        lda = (runs[a, R_ALPHA] + runs[a, R_BETA] * c) * sdot
        ldb = (runs[b, R_ALPHA] + runs[b, R_BETA] * c) * sdot
        txa, tza, txb, tzb = runs[a, R_TXE], runs[a, R_TZE], runs[b, R_TX], runs[b, R_TZ]
        ux, uz = runs[b, R_X] - runs[a, R_XE], runs[b, R_Z] - runs[a, R_ZE]
        dvx = (tab[kb, BX] - tab[ka, BX]) * ddot + txb * ldb - txa * lda
        dvz = (tab[kb, BZ] - tab[ka, BZ]) * ddot + tzb * ldb - tza * lda
        una = -ux * tza + uz * txa
        unb = -ux * tzb + uz * txb
        q = (
            (ux * txa + uz * tza) * q
            + tab[ka, KAPPA] * una * lda * lda
            - tab[kb, KAPPA] * unb * ldb * ldb
            - (dvx * dvx + dvz * dvz)
        ) / (ux * txb + uz * tzb)
        runs[b, R_Q] = q
    qg = (aux[A_GHOST + 2] + 2.0 * aux[A_GHOST + 3] * c) * sd2
    e = (qg - q) / (runs[g, R_BETA] - ldg)
    return c, e, (runs[g, R_BETA] - ldg) / lsg


@kernel(inline="always")
def run_roller(kap, x, z, tx, tz, j, step, cd, sg, ccx, ccz):
    """Roller j of a run (0: its first, at (x, z)) and its unit tangent: on a line j links of arc length
    ``step`` along the tangent (tx, tz); on an arc (curvature ``kap``, centre (ccx, ccz)) the previous
    roller's tangent (tx, tz) turned by one link (cosine ``cd``, sine ``sg``). (x, z, tx, tz)"""
    if kap == 0.0:
        return x + j * step * tx, z + j * step * tz, tx, tz
    if j > 0:
        tx, tz = tx * cd - tz * sg, tz * cd + tx * sg
    return ccx + tz / kap, ccz - tx / kap, tx, tz


@kernel()
def run_fill(tab, p0, n, delta, sdot, c, e, runs, aux, xs, zs, jac, hacc, s0, want_s0):
    """Every roller's place, J = dr/ds and h (a = J s-ddot + h) at roller-1 speed ``sdot`` from the
    closed walk and its rates (:func:`run_rates`); each roller's s0 as well where ``want_s0``."""
    nr = int(aux[A_RUNS])
    # every roller: J = B c + T g, h = B e + T (beta e + q) + kappa N lam-dot^2
    for r in range(nr):
        first, last = int(runs[r, R_FIRST]), int(runs[r, R_LAST])
        if last > n - 1:
            last = n - 1
        if first > last:
            continue
        k = int(runs[r, R_SEG])
        kap = tab[k, KAPPA]
        gr = runs[r, R_ALPHA] + runs[r, R_BETA] * c
        w = runs[r, R_BETA] * e + runs[r, R_Q]
        cen = kap * (gr * sdot) ** 2
        cbx, cbz, ebx, ebz = tab[k, BX] * c, tab[k, BZ] * c, tab[k, BX] * e, tab[k, BZ] * e
        x, z, tx, tz = runs[r, R_X], runs[r, R_Z], runs[r, R_TX], runs[r, R_TZ]
        step = runs[r, R_STEP]
        cx = cz = cd = sg = 0.0
        if kap != 0.0:
            cx, cz = x - tz / kap, z + tx / kap
            cd, sg = math.cos(kap * step), math.sin(kap * step)
        for i in range(first, last + 1):
            xs[i], zs[i], tx, tz = run_roller(kap, x, z, tx, tz, i - first, step, cd, sg, cx, cz)
            jac[i, 0] = cbx + tx * gr
            jac[i, 1] = cbz + tz * gr
            hacc[i, 0] = ebx + tx * w - tz * cen
            hacc[i, 1] = ebz + tz * w + tx * cen
            if want_s0:
                s0[i] = roller_s0(tab, p0, k, runs[r, R_LAM] + (i - first) * step, runs[r, R_WRAPS], delta)
        if first <= int(runs[r, R_LAST]) <= n - 1:
            # the run's last roller as the walk placed it (the rotations above agree to rounding)
            xs[last] = runs[r, R_XE]
            zs[last] = runs[r, R_ZE]
