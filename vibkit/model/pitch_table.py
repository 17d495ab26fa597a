"""The chain's configuration tabulated over one link pitch of travel, interpolated instead of solved.

With equal links and equal roller masses, the chain with roller 1 where roller 2 was is the same
chain relabelled: every chain-only quantity of the forward dynamics (the generalised mass, gravity's
work, the carriage, each roller's position and its derivatives) repeats, up to the labels, after
one pitch. So the closure need not be solved at each evaluation: it is solved once at the nodes of
one pitch of travel of roller 1, u in [a, phi(a)) (a the first breakpoint, phi(a) where roller 2
then sits), and interpolated between them.

Interpolation. Between consecutive breakpoints (where some roller crosses a curvature jump of the
guide: the only places where the configuration is not smooth) each piece gets quintic Hermite
polynomials in u from the exact positions, first and second derivatives at its ends (the chain's
velocity and acceleration recursions give them, :mod:`vibkit.model.chain`), one-sided at a
breakpoint; the generalised mass M(u) = sum m_i |dr_i/du|^2 + m_c (d delta/du)^2 gets one from M,
the exact dM/du and d2M/du2 by differences of the exact dM/du 1 um apart (third derivatives of the
positions are not computed). The reduced equation is then that of a one-degree-of-freedom
Lagrangian system with this M and the interpolated potentials, M u'' + M'(u) u'^2 / 2 = Q(u), so an
undamped chain conserves the tabulated chain's energy exactly.

Roller 1's coordinate s (the state) maps to the table through the pieces of the whole loop: for the
piece where table roller k crosses s, u(s) is the inverse of u -> s0_k(u), a quintic from
ds0_k/du and d2 s0_k/du^2 at its ends. Its pieces end exactly on the crossing values the integrator
stops at, so a stage on the far side of a breakpoint reads the far-side polynomial.

Error: the node spacing h is chosen from the tolerance (:func:`table_spacing`); the quintics err
as h^6 in the values and h^4 in the second derivatives (the accelerations), which is what the
right-hand side's error follows (10-16 times less per halving of h, measured): the chain's
accelerations change sharply near some breakpoints (speed ratios curving at 280 /m^2 within a few
mm), so the nodes are closer than smooth functions would need. ``tests/model/test_pitch_table.py``
measures the right-hand side against the exact closure.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..runtime.kernel import kernel
from .chain import acceleration_terms, close_with_slope, fill_partials, sensitivity, velocity_coefficients, walk_arrays
from .effects import (
    aboard,
    carries_all,
    clear_teeth,
    evaluate,
    finish,
    left_out,
    rolling_force,
    sprocket_contact,
    step_load,
    step_roller,
    within_reach,
)
from .runs_rhs import runs_evaluate
from .slots import (
    FP_CARRIAGE_MASS,
    FP_CLOSURE_TOL,
    FP_CX,
    FP_CZ,
    FP_DAMPING,
    FP_G,
    FP_LT,
    FP_P0,
    FP_PRELOAD,
    FP_REACH,
    FP_ROLLING,
    FP_TENSIONER_STIFFNESS,
    HEAD_A,
    HEAD_BY_ROLLER,
    HEAD_N,
    HEAD_NAMES,
    HEAD_P0,
    HEAD_PIECES,
    HEAD_RUNS,
    INFO_AT,
    INFO_CURVATURE,
    INFO_DELTA,
    INFO_DELTA_DDOT,
    INFO_DELTA_DOT,
    INFO_SLOPE,
    IP_CONTACT,
    IP_GRAVITY,
    IP_LINKS_PER_STEP,
    IP_PASSENGERS,
    IP_ROLLING,
    IP_TENSIONER,
    PASSENGERS_BY_TIME,
    PRM_IP,
    TB_CAND,
    TB_CC,
    TB_DC,
    TB_HEAD,
    TB_MC,
    TB_NAMES,
    TB_SB,
    TB_SC,
    TB_UC,
    TB_UP,
    TB_VC,
    TB_XC,
    TB_ZC,
)

__all__ = [
    "build_table",
    "empty_table",
    "table_evaluate",
    "table_delta",
    "rhs",
    "table_spacing",
    "table_applies",
    "TABLE_CARRIES",
]

#: the effects :func:`table_evaluate` carries (gravity in the tabulated potential or roller by roller,
#: the others as generalised forces); a scene with any other effect of the schema takes the exact closure
TABLE_CARRIES = frozenset({"gravity", "contact", "motor", "passengers", "tensioner", "rolling_resistance"})
TABLE_LEAVES = left_out(TABLE_CARRIES)

SIDE = 1e-9  # [m] a breakpoint node is evaluated this far inside its piece, then moved onto it by Taylor
FD = 1e-6  # [m] step of the differences that give d2M/du2 from the exact dM/du


def table_applies(model) -> str | None:
    """Why the table cannot stand for the closure on ``model`` (None when it can).

    Rollers of different masses or radii leave the chain's configuration repeating after one pitch
    (only the links' lengths place the rollers): the table then gives each roller's place, and the
    generalised mass, gravity's force and the contact are summed roller by roller with its own mass
    and radius."""
    pitches = np.asarray(model.chain.pitches)
    if not np.all(pitches == pitches[0]):
        return "the links' pitches differ (the chain does not repeat after one pitch)"
    return None


def _by_roller(model) -> bool:
    return not (np.all(model.mass == model.mass[0]) and np.all(model.radii == model.radii[0]))


def table_spacing(rtol: float) -> float:
    """Largest node spacing of the table at tolerance ``rtol``. [m]

    Measured on the no-load scene against the exact closure at rtol 1e-11
    (``benchmarks/pitch_table_spacing.py``): at 4 mm the chain, coasting after its last contact,
    drifts 0.25 mm ahead by 44 s at rtol 1e-7, where the exact closure's own drift is 6 um; at 2 mm
    and finer the drift is the exact closure's (3-12 um at rtol 1e-7 and 1e-9). The tighter
    tolerances of the convergence check get finer tables all the same.
    """
    if rtol >= 1e-8:
        return 2e-3
    if rtol >= 1e-10:
        return 1e-3
    return 5e-4


# --------------------------------------------------------------------------------------------
# building


@kernel()
def _node(
    tab, p0, lt, u, guess, slope, pitches, n, tol, s0, kk, lam, xs, zs, part, alpha, beta, jac, gam, hacc, eta, sd, out
):
    """Exact closure at roller-1 coordinate u, from a predicted delta and the last dh/ddelta
    ``slope`` (0: none); fills out (n + 1, 3, 3): for each roller (and, in row n, delta) its
    [x, z, s0] with first and second derivatives along u. Returns (delta, status); beta[n] is then
    dh/ddelta here."""
    d, _, st = close_with_slope(tab, p0, lt, u, guess, slope, pitches, n, s0, kk, lam, xs, zs, part, alpha, beta, tol)
    if st != 0:
        return d, st
    fill_partials(tab, p0, s0, kk, lam, d, n + 1, part)
    sensitivity(part, xs, zs, n + 1, alpha, beta)
    c = velocity_coefficients(part, xs, zs, n, alpha, beta, jac, gam)
    e = acceleration_terms(part, xs, zs, n, alpha, beta, gam, c, 1.0, hacc, eta, sd)
    for i in range(n):
        out[i, 0, 0] = xs[i]
        out[i, 0, 1] = jac[i, 0]
        out[i, 0, 2] = hacc[i, 0]
        out[i, 1, 0] = zs[i]
        out[i, 1, 1] = jac[i, 1]
        out[i, 1, 2] = hacc[i, 1]
        out[i, 2, 0] = s0[i]
        out[i, 2, 1] = gam[i]
        out[i, 2, 2] = beta[i] * e + eta[i]
    out[n, 0, 0] = d
    out[n, 0, 1] = c
    out[n, 0, 2] = e
    return d, 0


@kernel()
def _mass_slope(out, mroll, m_c):
    """dM/du of the generalised mass from a node's data (see _node)."""
    n = out.shape[0] - 1
    acc = 0.0
    for i in range(n):
        acc += out[i, 0, 1] * out[i, 0, 2] + out[i, 1, 1] * out[i, 1, 2]
    return 2.0 * mroll * acc + 2.0 * m_c * out[n, 0, 1] * out[n, 0, 2]


@nb.njit(cache=True, error_model="numpy")
def _nodes(tab, p0, lt, pts, inward, guess, pitches, n, tol, mroll, m_c, data, mdd):
    """Exact data (see _node) at each point of ``pts``, and d2M/du2 from differences of dM/du.

    Where ``inward`` is +-1 the point is a breakpoint and the data are those of the side it
    points to: taken SIDE inside and moved onto the point by Taylor, the second derivative of M
    by a one-sided difference. Returns the index of a point where the chain does not close, or -1.
    """
    s0, kk, lam, xs, zs, part, alpha, beta = walk_arrays(n)
    jac = np.empty((n, 2))
    gam = np.empty(n)
    hacc = np.empty((n, 2))
    eta = np.empty(n)
    sd = np.empty(n)
    tmp = np.empty((n + 1, 3, 3))
    d = guess
    slope = 0.0
    u_at, c_at, e_at = pts[0], 0.0, 0.0  # where the last node was, its d delta/du and d2 delta/du2
    for q in range(pts.size):
        side = inward[q]
        eps = side * SIDE
        out = data[q]
        u = pts[q] + eps
        du = u - u_at
        d, st = _node(
            tab,
            p0,
            lt,
            u,
            d + du * (c_at + 0.5 * e_at * du),
            slope,
            pitches,
            n,
            tol,
            s0,
            kk,
            lam,
            xs,
            zs,
            part,
            alpha,
            beta,
            jac,
            gam,
            hacc,
            eta,
            sd,
            out,
        )
        if st != 0:
            return q
        u_at, c_at, e_at, slope = u, out[n, 0, 1], out[n, 0, 2], beta[n]
        m0 = _mass_slope(out, mroll, m_c)
        # d2M/du2: a central difference, or on a breakpoint a one-sided one into the piece
        h1, h2 = (side * FD, 2.0 * side * FD) if side != 0.0 else (FD, -FD)
        _, st = _node(
            tab,
            p0,
            lt,
            u + h1,
            d + h1 * (c_at + 0.5 * e_at * h1),
            slope,
            pitches,
            n,
            tol,
            s0,
            kk,
            lam,
            xs,
            zs,
            part,
            alpha,
            beta,
            jac,
            gam,
            hacc,
            eta,
            sd,
            tmp,
        )
        m1 = _mass_slope(tmp, mroll, m_c)
        _, st2 = _node(
            tab,
            p0,
            lt,
            u + h2,
            d + h2 * (c_at + 0.5 * e_at * h2),
            slope,
            pitches,
            n,
            tol,
            s0,
            kk,
            lam,
            xs,
            zs,
            part,
            alpha,
            beta,
            jac,
            gam,
            hacc,
            eta,
            sd,
            tmp,
        )
        m2 = _mass_slope(tmp, mroll, m_c)
        if st != 0 or st2 != 0:
            return q
        if side != 0.0:
            mdd[q] = side * (-3.0 * m0 + 4.0 * m1 - m2) / (2.0 * FD)
            # onto the breakpoint by Taylor, from its own side
            for i in range(n + 1):
                for c in range(3):
                    out[i, c, 0] += -eps * out[i, c, 1] + 0.5 * eps * eps * out[i, c, 2]
                    out[i, c, 1] += -eps * out[i, c, 2]
        else:
            mdd[q] = (m1 - m2) / (2.0 * FD)
    return -1


def _quintic(f0, d0, dd0, f1, d1, dd1, h):
    """Coefficients (..., 6) in x in [0, 1] of the quintic with the given values and derivatives
    (along the original variable) at the ends of an interval of length h."""
    d0, d1, dd0, dd1 = d0 * h, d1 * h, dd0 * h * h, dd1 * h * h
    df = f1 - f0
    return np.stack(
        [
            f0,
            d0,
            0.5 * dd0,
            10.0 * df - 6.0 * d0 - 4.0 * d1 - 1.5 * dd0 + 0.5 * dd1,
            -15.0 * df + 8.0 * d0 + 7.0 * d1 + 1.5 * dd0 - dd1,
            6.0 * df - 3.0 * d0 - 3.0 * d1 - 0.5 * dd0 + 0.5 * dd1,
        ],
        axis=-1,
    )


def build_table(model, prm, cross, spacing):
    """The table of ``model`` for the parameters ``prm`` (:func:`vibkit.model.effects.pack_parameters`)
    with node spacing ``spacing`` [m]; ``cross`` the sorted crossing values of one loop
    (:meth:`vibkit.model.chain.Chain.crossing_table`), which become piece ends."""
    tab, _, fp, ip, mass, *_ = prm
    chain = model.chain
    n = model.n
    p0 = float(fp[FP_P0])
    cross = np.sort(np.mod(np.asarray(cross, dtype=float), p0))
    a = float(cross[0]) if cross.size else 0.0
    start = chain.configure(a)  # roller 1 on the first breakpoint: where roller 2 sits ends the pitch
    b = float(start.s0[1])
    bps = cross[(cross > a) & (cross < b - 1e-10)]
    edges = np.concatenate([[a], bps, [b]])
    # the pieces: each interval between breakpoints cut in equal parts no longer than spacing
    nodes, is_bp = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = max(1, math.ceil((hi - lo) / spacing))
        nodes += list(lo + (hi - lo) * np.arange(m) / m)
        is_bp += [True] + [False] * (m - 1)
    nodes.append(b)
    is_bp.append(True)
    up = np.asarray(nodes)
    npc = up.size - 1
    # exact data at each piece's two ends (one-sided on a breakpoint: two evaluations there)
    pts, inward, slot = [], [], np.empty((npc, 2), dtype=np.int64)
    for j in range(up.size):
        for side, into in ((0, 1.0), (1, -1.0)):  # the start of piece j, the end of piece j - 1
            p = j if side == 0 else j - 1
            if not 0 <= p < npc:
                continue
            if is_bp[j] or side == 0 or j == up.size - 1:
                pts.append(up[j])
                inward.append(into if is_bp[j] else 0.0)
            slot[p, side] = len(pts) - 1
    mroll = float(mass[0])
    m_c = float(fp[FP_CARRIAGE_MASS]) if ip[IP_TENSIONER] == 1 else 0.0
    data = np.zeros((len(pts), n + 1, 3, 3))
    mdd_pt = np.empty(len(pts))
    bad = _nodes(
        tab,
        p0,
        fp[FP_LT],
        np.asarray(pts),
        np.asarray(inward),
        start.delta,
        chain.pitches,
        n,
        fp[FP_CLOSURE_TOL],
        mroll,
        m_c,
        data,
        mdd_pt,
    )
    if bad >= 0:
        raise ValueError(f"the chain could not be closed at s0_1 = {pts[bad]:.9g} m")
    ends = data[slot]  # (npc, 2, n + 1, 3, 3)
    mdd = mdd_pt[slot]
    hu = np.diff(up)
    g = float(fp[FP_G]) if ip[IP_GRAVITY] == 1 else 0.0
    x, z, s = ends[:, :, :n, 0, :], ends[:, :, :n, 1, :], ends[:, :, :n, 2, :]  # (npc, 2, n, 3)
    dl = ends[:, :, n, 0, :]  # delta, d delta/du, d2 delta/du2: (npc, 2, 3)
    mm = mroll * (x[..., 1] ** 2 + z[..., 1] ** 2).sum(-1) + m_c * dl[..., 1] ** 2
    mp = 2.0 * mroll * (x[..., 1] * x[..., 2] + z[..., 1] * z[..., 2]).sum(-1) + 2.0 * m_c * dl[..., 1] * dl[..., 2]
    vg = g * mroll * np.stack([z[..., k].sum(-1) for k in range(3)], axis=-1)  # (npc, 2, 3)

    def q5(f):  # f (npc, 2, ..., 3) -> (npc, ..., 6)
        h = hu.reshape((-1,) + (1,) * (f.ndim - 3))
        return _quintic(
            f[:, 0, ..., 0], f[:, 0, ..., 1], f[:, 0, ..., 2], f[:, 1, ..., 0], f[:, 1, ..., 1], f[:, 1, ..., 2], h
        )

    mc = _quintic(mm[:, 0], mp[:, 0], mdd[:, 0], mm[:, 1], mp[:, 1], mdd[:, 1], hu)
    vc = q5(vg)
    dc = q5(dl)
    xc = np.ascontiguousarray(np.moveaxis(q5(x), 0, 1))  # (n, npc, 6)
    zc = np.ascontiguousarray(np.moveaxis(q5(z), 0, 1))
    sc = np.ascontiguousarray(np.moveaxis(q5(s), 0, 1))
    # the whole loop: piece (k, p) where table roller k crosses roller 1's coordinate, k-major
    s_lo = s[:, 0, :, 0].T  # (n, npc): s0_k at the start of piece p
    s_hi = s[:, 1, :, 0].T
    sb = np.append(s_lo.ravel(), a + p0)
    # ends on the integrator's crossing values, exactly
    ext = np.concatenate([cross, cross + p0])
    near = np.clip(np.searchsorted(ext, sb), 1, ext.size - 1)
    pick = np.where(np.abs(ext[near] - sb) < np.abs(ext[near - 1] - sb), near, near - 1)
    snap = np.abs(ext[pick] - sb) < 1e-9
    sb[snap] = ext[pick[snap]]
    gk = s[:, :, :, 1]  # ds0_k/du (npc, 2, n)
    tk = s[:, :, :, 2]
    du = 1.0 / gk
    ddu = -tk / gk**3
    hs = np.diff(sb).reshape(n, npc)
    if np.any(hs <= 0.0) or np.any(np.abs(s_hi - s_lo - hs) > 1e-9):
        raise ValueError("the pitch table's pieces do not tile the loop")
    uc = _quintic(
        np.zeros((n, npc)), du[:, 0].T, ddu[:, 0].T, np.broadcast_to(hu, (n, npc)), du[:, 1].T, ddu[:, 1].T, hs
    ).reshape(n * npc, 6)
    # contact candidates: table rollers that come within reach of a tooth anywhere in the pitch
    reach = float(fp[FP_REACH]) + 2.0 * spacing + 1e-6
    dist = np.hypot(x[..., 0] - fp[FP_CX], z[..., 0] - fp[FP_CZ])  # (npc, 2, n)
    cand = np.flatnonzero((dist < reach).any(axis=(0, 1))).astype(np.int64)
    # the candidates' x and z polynomials side by side, piece by piece: one evaluation reads one block
    cc = np.ascontiguousarray(np.concatenate([xc[cand], zc[cand]], axis=-1).transpose(1, 0, 2))
    head = np.array([a, p0, float(npc), float(n), _link_error(xc, zc, chain.pitches), float(_by_roller(model)), 0.0])
    if head.size != len(HEAD_NAMES):
        raise RuntimeError("the table's header and vibkit.model.slots.HEAD_NAMES disagree")
    tb = (
        head,
        np.ascontiguousarray(sb),
        np.ascontiguousarray(uc),
        up,
        mc,
        vc,
        dc,
        xc,
        zc,
        sc,
        cand,
        cc,
    ) + empty_table()[12:]
    if len(tb) != len(TB_NAMES):
        raise RuntimeError("the table and vibkit.model.slots.TB_NAMES disagree")
    return tb


def _link_error(xc, zc, pitches):
    """Largest | |r_{i+1} - r_i| - L_i | of the tabulated chain at the quarter points of every
    piece: the table's own closure residual. [m]"""
    worst = 0.0
    for x in (0.25, 0.5, 0.75):
        powers = x ** np.arange(6)
        px, pz = xc @ powers, zc @ powers  # (n, npc)
        length = np.hypot(np.roll(px, -1, axis=0) - px, np.roll(pz, -1, axis=0) - pz)
        worst = max(worst, float(np.max(np.abs(length - pitches[:, None]))))
    return worst


def empty_table():
    """The table's shape with nothing in it (the exact closure is used)."""
    z1, z2, z3 = np.zeros(0), np.zeros((0, 6)), np.zeros((0, 0, 6))
    return (
        np.zeros(len(HEAD_NAMES)),
        z1,
        z2,
        z1,
        z2,
        z2,
        z2,
        z3,
        z3,
        z3,
        np.zeros(0, dtype=np.int64),
        np.zeros((0, 0, 12)),
        np.zeros((0, 5)),
        np.zeros(0, dtype=np.int64),
        np.zeros((0, 17)),
        z1,
    )


# --------------------------------------------------------------------------------------------
# evaluation


@kernel(inline="always")
def _p5(c, r, x):
    """Value, d/dx and d2/dx2 at x of the quintic with coefficients c[r] (indexed, not sliced:
    a slice costs more than the polynomial)."""
    c0, c1, c2, c3, c4, c5 = c[r, 0], c[r, 1], c[r, 2], c[r, 3], c[r, 4], c[r, 5]
    v = c0 + x * (c1 + x * (c2 + x * (c3 + x * (c4 + x * c5))))
    d = c1 + x * (2.0 * c2 + x * (3.0 * c3 + x * (4.0 * c4 + x * 5.0 * c5)))
    dd = 2.0 * c2 + x * (6.0 * c3 + x * (12.0 * c4 + x * 20.0 * c5))
    return v, d, dd


@kernel(inline="always")
def _p5d(c, i, r, x, o=0):
    """Value and d/dx at x of the quintic with coefficients c[i, r, o:o + 6]."""
    c0, c1, c2, c3, c4, c5 = c[i, r, o], c[i, r, o + 1], c[i, r, o + 2], c[i, r, o + 3], c[i, r, o + 4], c[i, r, o + 5]
    v = c0 + x * (c1 + x * (c2 + x * (c3 + x * (c4 + x * c5))))
    d = c1 + x * (2.0 * c2 + x * (3.0 * c3 + x * (4.0 * c4 + x * 5.0 * c5)))
    return v, d


@kernel()
def locate(tb, s):
    """Where roller 1 at s sits in the table: (piece p, table roller k of roller 1, loops W,
    eta in [0, 1] along piece p, du/ds, d2u/ds2)."""
    head, sb, uc, up = tb[TB_HEAD], tb[TB_SB], tb[TB_UC], tb[TB_UP]
    a, p0, npc = head[HEAD_A], head[HEAD_P0], int(head[HEAD_PIECES])
    w = math.floor((s - a) / p0)
    r = s - w * p0
    j = np.searchsorted(sb, r, side="right") - 1
    if j < 0:
        j = 0
    elif j > sb.size - 2:
        j = sb.size - 2
    k = j // npc
    p = j - k * npc
    hs = sb[j + 1] - sb[j]
    off, d, dd = _p5(uc, j, (r - sb[j]) / hs)
    hu = up[p + 1] - up[p]
    eta = off / hu
    if eta < 0.0:
        eta = 0.0
    elif eta > 1.0:
        eta = 1.0
    return p, k, w, eta, d / hs, dd / (hs * hs)


@kernel()
def table_delta(tb, s):
    """delta [m] with roller 1 at s, from the table."""
    p, _, _, eta, _, _ = locate(tb, s)
    return _p5(tb[TB_DC], p, eta)[0]


@kernel(inline="always")
def _p5dd(c, i, r, x):
    """d/dx and d2/dx2 at x of the quintic with coefficients c[i, r, :]."""
    c1, c2, c3, c4, c5 = c[i, r, 1], c[i, r, 2], c[i, r, 3], c[i, r, 4], c[i, r, 5]
    d = c1 + x * (2.0 * c2 + x * (3.0 * c3 + x * (4.0 * c4 + x * 5.0 * c5)))
    dd = 2.0 * c2 + x * (6.0 * c3 + x * (12.0 * c4 + x * 20.0 * c5))
    return d, dd


@kernel()
def _mass_by_roller(xc, zc, p, eta, hu, k, n, mass, fp, ip, d_u, d_uu):
    """Generalised mass M(u), dM/du and gravity's generalised force -dV/du summed over the table's
    rollers, each with the mass of the chain's roller it is (chain roller i is table roller i + k);
    ``d_u``, ``d_uu``: d delta/du and d2 delta/du2."""
    m_j = 0.0
    m_jh = 0.0
    m_z = 0.0
    for t in range(n):
        mi = mass[(t - k) % n]
        jx, hx = _p5dd(xc, t, p, eta)
        jz, hz = _p5dd(zc, t, p, eta)
        m_j += mi * (jx * jx + jz * jz)
        m_jh += mi * (jx * hx + jz * hz)
        m_z += mi * jz
    m_c = fp[FP_CARRIAGE_MASS] if ip[IP_TENSIONER] == 1 else 0.0
    g = fp[FP_G] if ip[IP_GRAVITY] == 1 else 0.0
    h2 = hu * hu
    m_u = m_j / h2 + m_c * d_u * d_u
    mp_u = 2.0 * m_jh / (h2 * hu) + 2.0 * m_c * d_u * d_uu
    return m_u, mp_u, -g * m_z / hu


@kernel()
def table_evaluate(t, y, dy, prm, ws, want_teeth, tb):
    """Right-hand side of the forward dynamics from the table: the same equations and the same
    ``info`` slots as :func:`vibkit.model.effects.evaluate` (delta, its rates, motor and contact
    quantities), with the closure read from the table instead of solved. Only the contact
    candidates' positions land in ``ws``. Returns 0."""
    _, loc, fp, ip, mass, pm, ps, pb, pa, _, radii, _ = prm
    (_, _, _, xs, zs, _, _, _, jac, _, _, vxs, vzs, fx, fz, cand, ind_t, frc_t, info) = ws
    head, up, mc, vc, dc = tb[TB_HEAD], tb[TB_UP], tb[TB_MC], tb[TB_VC], tb[TB_DC]
    xc, zc, sc, cand0, cc = tb[TB_XC], tb[TB_ZC], tb[TB_SC], tb[TB_CAND], tb[TB_CC]
    p0 = head[HEAD_P0]
    n = int(head[HEAD_N])
    s, sdot = y[0], y[1]
    p, k, w, eta, us, uss = locate(tb, s)
    hu = up[p + 1] - up[p]
    udot = us * sdot
    delta, d_u, d_uu = _p5(dc, p, eta)
    d_u /= hu
    d_uu /= hu * hu
    if head[HEAD_BY_ROLLER] == 0.0:
        m_u, mp_u, _ = _p5(mc, p, eta)
        mp_u /= hu
        _, v_u, _ = _p5(vc, p, eta)
        q = -v_u / hu
    else:
        m_u, mp_u, q = _mass_by_roller(xc, zc, p, eta, hu, k, n, mass, fp, ip, d_u, d_uu)
    if ip[IP_TENSIONER] == 1:
        q -= (fp[FP_PRELOAD] + fp[FP_TENSIONER_STIFFNESS] * delta) * d_u
    g = fp[FP_G]
    if ip[IP_PASSENGERS] != 0:
        kstep = ip[IP_LINKS_PER_STEP]
        # the passengers' loads (vibkit.model.effects.passenger_loads) as generalised forces: the
        # chain's roller i is table roller i + k, its place read from the table
        for jp in range(pm.size):
            if ip[IP_PASSENGERS] == PASSENGERS_BY_TIME:
                where = t
            else:
                tk = step_roller(ps, jp, 1, n, kstep) + k
                where = _p5d(sc, tk % n, p, eta)[0] + (p0 if tk >= n else 0.0) + w * p0
            if aboard(jp, where, pb, pa):
                load = step_load(jp, pm, g, kstep)
                for r in range(kstep):
                    i = (step_roller(ps, jp, r, n, kstep) + k) % n
                    q -= load * _p5d(zc, i, p, eta)[1] / hu
    if ip[IP_ROLLING] == 1:
        mu = fp[FP_ROLLING]
        for i in range(n):
            jx = _p5d(xc, i, p, eta)[1] / hu
            jz = _p5d(zc, i, p, eta)[1] / hu
            rx, rz = rolling_force(jx * udot, jz * udot, mu * mass[(i - k) % n] * g)
            q += jx * rx + jz * rz
    torque_c, energy_c, worst, active, f_drive, f_back = 0.0, 0.0, 0.0, 0, 0.0, 0.0
    if want_teeth:
        clear_teeth(ind_t, frc_t)
    if ip[IP_CONTACT] == 1:
        # the candidates of vibkit.model.effects.contact_candidates among the table's candidates
        ncand = 0
        reach = fp[FP_REACH] + 1e-9
        reach2 = reach * reach
        for jj in range(cand0.size):
            i = (cand0[jj] - k) % n  # the chain's roller that is this table roller: its own radius
            x, jx = _p5d(cc, p, jj, eta)
            z, jz = _p5d(cc, p, jj, eta, 6)
            if within_reach(x, z, fp[FP_CX], fp[FP_CZ], reach2):
                xs[i] = x
                zs[i] = z
                jac[i, 0] = jx / hu
                jac[i, 1] = jz / hu
                vxs[i] = jac[i, 0] * udot
                vzs[i] = jac[i, 1] * udot
                fx[i] = 0.0
                fz[i] = 0.0
                cand[ncand] = i
                ncand += 1
        torque_c, energy_c, worst, active, f_drive, f_back = sprocket_contact(
            prm, y, xs, zs, vxs, vzs, cand, ncand, fp[FP_DAMPING], fx, fz, ind_t, frc_t, want_teeth
        )
        for jj in range(ncand):
            i = cand[jj]
            q += jac[i, 0] * fx[i] + jac[i, 1] * fz[i]
    uddot = (q - 0.5 * mp_u * udot * udot) / m_u
    sddot = (uddot - uss * sdot * sdot) / us
    finish(y, dy, info, fp, ip, sddot, torque_c, energy_c, worst, active, f_drive, f_back)
    c_s = d_u * us
    info[INFO_DELTA] = delta
    info[INFO_DELTA_DOT] = c_s * sdot
    info[INFO_DELTA_DDOT] = d_u * uddot + d_uu * udot * udot
    info[INFO_AT] = s
    info[INFO_SLOPE] = c_s
    info[INFO_CURVATURE] = d_uu * us * us + d_u * uss
    return 0


@kernel(nogil=True)
def rhs(t, y, dy, prm, ws, want_teeth, tb):
    """The forward right-hand side: from the table ``tb`` where it has pieces, else from the exact
    closure (:func:`vibkit.model.effects.evaluate`), or walked run by run where the table's head says
    so (:func:`vibkit.model.runs.runs_evaluate`). A scene with an effect the table does not carry
    (:data:`TABLE_CARRIES`) takes the exact closure. Returns the status (0 ok)."""
    if tb[TB_HEAD][HEAD_RUNS] != 0.0:
        return runs_evaluate(t, y, dy, prm, ws, want_teeth, tb)
    if tb[TB_SB].size > 0 and carries_all(prm[PRM_IP], TABLE_LEAVES):
        return table_evaluate(t, y, dy, prm, ws, want_teeth, tb)
    return evaluate(t, y, dy, prm, ws, want_teeth)
