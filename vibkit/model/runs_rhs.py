"""The forward right-hand side from the chain closed run by run (:mod:`vibkit.model.runs`).

:func:`runs_evaluate` closes the chain run by run and hands every roller's place, J and h to the
exact closure's forces (:func:`vibkit.model.effects.evaluate_forces`). For rollers of one mass,
with only the effects it carries (:data:`FAST_CARRIES`), :func:`runs_fast` takes each run's share of the reduced
equation in closed form instead (a run moves as one body: J_j = B c + T_j g, h_j = B e + T_j w +
kappa N_j lam-dot^2, so its sums need only the sum of its tangents, which on an arc is a geometric
sum), and places one by one only the rollers of the runs that can reach the sprocket. Both are the
exact closure's equations, to rounding. :func:`build_runs` packs what they need into the pitch
table's tuple, its head marked.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..runtime.kernel import kernel
from .chain import closure_residual
from .effects import (
    carries_all,
    clear_teeth,
    evaluate,
    evaluate_forces,
    finish,
    left_out,
    remember_closure,
    sprocket_contact,
    within_reach,
)
from .guide import BX, BZ, KAPPA, local_frame, seg_length
from .runs import (
    A_COLS,
    A_RUNS,
    R_ALPHA,
    R_BETA,
    R_COLS,
    R_FIRST,
    R_LAST,
    R_Q,
    R_SEG,
    R_STEP,
    R_TX,
    R_TZ,
    R_X,
    R_Z,
    RS_COS,
    RS_NEAR,
    RS_SIN,
    RS_SIN_HALF,
    TURNS,
    next_other,
    nominal_pitch,
    run_close,
    run_fill,
    run_rates,
    run_roller,
    run_steps,
    run_walk,
)
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
    FP_TENSIONER_STIFFNESS,
    HEAD_BY_ROLLER,
    HEAD_LINK_ERROR,
    HEAD_NAMES,
    HEAD_RUNS,
    INFO_AT,
    INFO_CURVATURE,
    INFO_DELTA,
    INFO_SLOPE,
    INFO_WALKS,
    IP_CONTACT,
    IP_GRAVITY,
    IP_N,
    IP_PASSENGERS,
    IP_TENSIONER,
    PASSENGERS_BY_PLACE,
    PRM_FP,
    PRM_IP,
    PRM_PITCHES,
    PRM_TABLE,
    TB_HEAD,
    TB_RAUX,
    TB_RNEXT,
    TB_RSTEP,
    TB_RUNS,
    WS_HACC,
    WS_INFO,
    WS_JAC,
    WS_S0,
    WS_X,
    WS_Z,
)

__all__ = ["build_runs", "runs_evaluate", "runs_fast", "runs_observe", "FAST_CARRIES"]

#: the effects :func:`runs_fast` carries in closed form; a scene with any other effect of the schema
#: (passengers, rolling resistance, or one added later) takes the exact closure's forces instead
FAST_CARRIES = frozenset({"gravity", "contact", "motor", "tensioner"})
FAST_LEAVES = left_out(FAST_CARRIES)


@kernel(inline="always")
def _close(y, prm, tb, info):
    """The closure from delta predicted along the last evaluation's slope and curvature."""
    tab, fp, ip, pitches = prm[PRM_TABLE], prm[PRM_FP], prm[PRM_IP], prm[PRM_PITCHES]
    ds = y[0] - info[INFO_AT]
    guess = info[INFO_DELTA] + ds * (info[INFO_SLOPE] + 0.5 * info[INFO_CURVATURE] * ds)
    return run_close(
        tab,
        fp[FP_P0],
        y[0],
        guess,
        pitches,
        ip[IP_N],
        fp[FP_CLOSURE_TOL],
        tb[TB_RSTEP],
        tb[TB_RNEXT],
        tb[TB_RUNS],
        tb[TB_RAUX],
    )


@kernel(inline="always")
def _contact(prm, y, xs, zs, vxs, vzs, cand, ncand, damping, fx, fz, ind_t, frc_t, want_teeth):
    """The sprocket's contact on the ``ncand`` candidates where the scene has it (what
    :func:`vibkit.model.effects.sprocket_contact` returns, zeros otherwise), the per-tooth arrays cleared
    first with ``want_teeth``."""
    if want_teeth:
        clear_teeth(ind_t, frc_t)
    if prm[PRM_IP][IP_CONTACT] != 1:
        return 0.0, 0.0, 0.0, 0, 0.0, 0.0
    return sprocket_contact(prm, y, xs, zs, vxs, vzs, cand, ncand, damping, fx, fz, ind_t, frc_t, want_teeth)


@kernel(inline="always")
def runs_evaluate(t, y, dy, prm, ws, want_teeth, tb):
    """Right-hand side of the forward dynamics from the closure walked run by run: the same
    equations, work arrays and ``info`` slots as :func:`vibkit.model.effects.evaluate` (which it
    falls back to where Newton's method from the predicted delta does not close). Returns 0, or 1
    where the chain cannot close."""
    tab, fp, ip = prm[PRM_TABLE], prm[PRM_FP], prm[PRM_IP]
    info = ws[WS_INFO]
    if tb[TB_HEAD][HEAD_BY_ROLLER] == 0.0 and carries_all(ip, FAST_LEAVES):
        return runs_fast(t, y, dy, prm, ws, want_teeth, tb)
    delta, walks, st = _close(y, prm, tb, info)
    if st != 0:
        return evaluate(t, y, dy, prm, ws, want_teeth)
    info[INFO_WALKS] += walks
    runs, aux = tb[TB_RUNS], tb[TB_RAUX]
    c, e, dh = run_rates(tab, y[1], runs, aux)
    want_s0 = ip[IP_PASSENGERS] == PASSENGERS_BY_PLACE
    xs, zs, jac, hacc = ws[WS_X], ws[WS_Z], ws[WS_JAC], ws[WS_HACC]
    run_fill(tab, fp[FP_P0], ip[IP_N], delta, y[1], c, e, runs, aux, xs, zs, jac, hacc, ws[WS_S0], want_s0)
    return evaluate_forces(t, y, dy, prm, ws, want_teeth, delta, c, e, dh)


@kernel(inline="always")
def runs_fast(t, y, dy, prm, ws, want_teeth, tb):
    """:func:`runs_evaluate` for rollers of one mass with only the effects of :data:`FAST_CARRIES`: each
    run's share of the reduced equation in closed form, rollers placed one by one only on the
    segments within the sprocket's reach. Returns 0, or 1 where the chain cannot close."""
    tab, loc, fp, ip, mass, pm, ps, pb, pa, pitches, radii, _ = prm
    (s0, kk, lam, xs, zs, part, _, _, jac, gam, hacc, vxs, vzs, fx, fz, cand, ind_t, frc_t, info) = ws
    delta, walks, st = _close(y, prm, tb, info)
    if st != 0:
        return evaluate(t, y, dy, prm, ws, want_teeth)
    info[INFO_WALKS] += walks
    runs, aux, rstep = tb[TB_RUNS], tb[TB_RAUX], tb[TB_RSTEP]
    n = ip[IP_N]
    sdot = y[1]
    c, e, dh = run_rates(tab, sdot, runs, aux)
    grav = fp[FP_G] if ip[IP_GRAVITY] == 1 else 0.0
    m = mass[0]
    contact = ip[IP_CONTACT] == 1
    reach = fp[FP_REACH] + 1e-9
    reach2 = reach * reach
    cx0, cz0 = fp[FP_CX], fp[FP_CZ]
    m_eff = 0.0
    q = 0.0
    ncand = 0
    for r in range(int(aux[A_RUNS])):
        first, last = int(runs[r, R_FIRST]), int(runs[r, R_LAST])
        if last > n - 1:
            last = n - 1
        if first > last:
            continue
        cnt = last - first + 1
        k = int(runs[r, R_SEG])
        kap = tab[k, KAPPA]
        g = runs[r, R_ALPHA] + runs[r, R_BETA] * c
        w = runs[r, R_BETA] * e + runs[r, R_Q]
        cen = kap * (g * sdot) ** 2
        bx, bz = tab[k, BX], tab[k, BZ]
        tx, tz = runs[r, R_TX], runs[r, R_TZ]
        # the sum of the run's tangents (on an arc each is the last turned by the link's angle)
        if kap == 0.0 or cnt == 1:
            stx, stz = cnt * tx, cnt * tz
        else:
            # sin(cnt h) / sin(h) and the turn by (cnt - 1) h, h the half-angle of one link
            f = rstep[k, TURNS + 2 * cnt + 1] / rstep[k, RS_SIN_HALF]
            ct, sn = rstep[k, TURNS + 2 * cnt - 2], rstep[k, TURNS + 2 * cnt - 1]
            stx, stz = f * (tx * ct - tz * sn), f * (tz * ct + tx * sn)
        bst = bx * stx + bz * stz
        bsn = -bx * stz + bz * stx
        bb = bx * bx + bz * bz
        m_eff += m * (cnt * (bb * c * c + g * g) + 2.0 * c * g * bst)
        jh = cnt * bb * c * e + (c * w + g * e) * bst + c * cen * bsn + cnt * g * w
        q -= m * (grav * (cnt * bz * c + g * stz) + jh)
        if contact and rstep[k, RS_NEAR] != 0.0:
            x, z, step = runs[r, R_X], runs[r, R_Z], runs[r, R_STEP]
            ccx = ccz = 0.0
            if kap != 0.0:
                ccx, ccz = x - tz / kap, z + tx / kap
            cd, sg = rstep[k, RS_COS], rstep[k, RS_SIN]
            for i in range(first, last + 1):
                xi, zi, tx, tz = run_roller(kap, x, z, tx, tz, i - first, step, cd, sg, ccx, ccz)
                if within_reach(xi, zi, cx0, cz0, reach2):
                    xs[i] = xi
                    zs[i] = zi
                    jac[i, 0] = bx * c + tx * g
                    jac[i, 1] = bz * c + tz * g
                    vxs[i] = jac[i, 0] * sdot
                    vzs[i] = jac[i, 1] * sdot
                    fx[i] = 0.0
                    fz[i] = 0.0
                    cand[ncand] = i
                    ncand += 1
    torque_c, energy_c, worst, active, f_drive, f_back = _contact(
        prm, y, xs, zs, vxs, vzs, cand, ncand, fp[FP_DAMPING], fx, fz, ind_t, frc_t, want_teeth
    )
    if contact:
        for jj in range(ncand):
            i = cand[jj]
            q += jac[i, 0] * fx[i] + jac[i, 1] * fz[i]
    if ip[IP_TENSIONER] == 1:
        m_c = fp[FP_CARRIAGE_MASS]
        m_eff += m_c * c * c
        q += c * (-(fp[FP_PRELOAD] + fp[FP_TENSIONER_STIFFNESS] * delta) - m_c * e)
    sddot = q / m_eff
    finish(y, dy, info, fp, ip, sddot, torque_c, energy_c, worst, active, f_drive, f_back)
    remember_closure(info, y, sddot, delta, c, e, dh)
    return 0


LINEAR_SHIFT = 1e-7  # [m] the largest Newton step runs_observe takes by a first-order shift instead of a walk


@kernel()
def runs_observe(t, y, dy, prm, ws, want_teeth, tb):
    """What an output needs of the positions alone (delta, the contact forces without damping, the
    motor torque) from one walk: where the walk from the predicted delta leaves a Newton step under
    ``LINEAR_SHIFT``, delta and the rollers within the sprocket's reach are moved by it to first
    order (each run rigidly: r += step (B_k + T beta), beta its lam's rate with delta), which leaves
    an error of order step^2 (below 1e-13 m); otherwise the exact closure (:func:`runs_evaluate`).
    Fills ``info`` as an evaluation does (delta, motor, flank forces, the prediction's memory) and
    ``ind_t``, ``frc_t`` with ``want_teeth``; ``dy`` is scratch. Returns 0, or 1 where the chain cannot
    close."""
    tab, fp, ip, pitches = prm[PRM_TABLE], prm[PRM_FP], prm[PRM_IP], prm[PRM_PITCHES]
    (_, _, _, xs, zs, _, _, _, _, _, _, vxs, vzs, fx, fz, cand, ind_t, frc_t, info) = ws
    runs, aux, rstep = tb[TB_RUNS], tb[TB_RAUX], tb[TB_RSTEP]
    n = ip[IP_N]
    ds = y[0] - info[INFO_AT]
    d = info[INFO_DELTA] + ds * (info[INFO_SLOPE] + 0.5 * info[INFO_CURVATURE] * ds)
    h, dh = run_walk(tab, fp[FP_P0], y[0], d, pitches, n, rstep, tb[TB_RNEXT], runs, aux, 0)
    if math.isnan(h) or not dh > 0.0 or abs(h) > LINEAR_SHIFT * dh:
        return runs_evaluate(t, y, dy, prm, ws, want_teeth, tb)
    info[INFO_WALKS] += 1
    shift = -h / dh if abs(h) > fp[FP_CLOSURE_TOL] else 0.0
    sdot = y[1]
    c, e, _ = run_rates(tab, sdot, runs, aux)
    reach = fp[FP_REACH] + 1e-9
    reach2 = reach * reach
    cx0, cz0 = fp[FP_CX], fp[FP_CZ]
    ncand = 0
    for r in range(int(aux[A_RUNS])):
        k = int(runs[r, R_SEG])
        first, last = int(runs[r, R_FIRST]), min(int(runs[r, R_LAST]), n - 1)
        if rstep[k, RS_NEAR] == 0.0 or first > last:
            continue
        kap = tab[k, KAPPA]
        x, z, tx, tz, step = runs[r, R_X], runs[r, R_Z], runs[r, R_TX], runs[r, R_TZ], runs[r, R_STEP]
        mx, mz, be = shift * tab[k, BX], shift * tab[k, BZ], shift * runs[r, R_BETA]
        ccx = ccz = 0.0
        if kap != 0.0:
            ccx, ccz = x - tz / kap, z + tx / kap
        cd, sg = rstep[k, RS_COS], rstep[k, RS_SIN]
        for i in range(first, last + 1):
            xi, zi, tx, tz = run_roller(kap, x, z, tx, tz, i - first, step, cd, sg, ccx, ccz)
            xi += mx + be * tx
            zi += mz + be * tz
            if within_reach(xi, zi, cx0, cz0, reach2):
                xs[i] = xi
                zs[i] = zi
                fx[i] = 0.0
                fz[i] = 0.0
                cand[ncand] = i
                ncand += 1
    torque_c, energy_c, worst, active, f_drive, f_back = _contact(
        prm, y, xs, zs, vxs, vzs, cand, ncand, 0.0, fx, fz, ind_t, frc_t, want_teeth
    )
    # the motor and contact slots as an evaluation leaves them (s-ddot is not computed: 0)
    finish(y, dy, info, fp, ip, 0.0, torque_c, energy_c, worst, active, f_drive, f_back)
    remember_closure(info, y, 0.0, d + shift, c, e, dh)
    return 0


@nb.njit(cache=True, error_model="numpy")
def _near(tab, cx, cz, reach, lt):
    """1.0 for each segment with a point closer than ``reach`` to the sprocket's centre (cx, cz), at
    any delta of the tensioner's travel (half-length ``lt``), sampled every few millimetres. (nseg,)"""
    near = np.zeros(tab.shape[0])
    for k in range(tab.shape[0]):
        for delta in (-0.9 * lt, 0.0, 0.9 * lt):
            length = seg_length(tab, k, delta)
            m = int(length / 0.002) + 2
            for j in range(m):
                x, z, _, _ = local_frame(tab, k, length * j / (m - 1), delta)
                if math.hypot(x - cx, z - cz) < reach:
                    near[k] = 1.0
    return near


def build_runs(model, prm, empty, s, delta):
    """The run-by-run closure's data for ``model`` in the pitch table's tuple ``empty`` (an empty
    table, :func:`vibkit.model.pitch_table.empty_table`): the head marked, each segment's step for
    the links most of the chain has (and whether it is within the sprocket's reach), where the other
    links are, scratch for the walk. The head's link error is the walk's own (the largest
    ``| |r_{i+1} - r_i| - L_i |``) closed at roller-1 coordinate ``s`` from ``delta``. [m]"""
    pitches = np.asarray(model.chain.pitches, dtype=float)
    n = pitches.size
    tab = model.guide.table
    fp = prm[PRM_FP]
    head = empty[TB_HEAD].copy()
    if head.size != len(HEAD_NAMES):
        raise RuntimeError("the table's header and vibkit.model.slots.HEAD_NAMES disagree")
    head[HEAD_RUNS] = 1.0
    head[HEAD_BY_ROLLER] = float(not np.all(model.mass == model.mass[0]))
    nominal = nominal_pitch(pitches)
    rstep = run_steps(tab, nominal, n)
    rstep[:, RS_NEAR] = _near(tab, fp[FP_CX], fp[FP_CZ], fp[FP_REACH] + float(pitches.max()) + 1e-3, fp[FP_LT])
    tb = list(empty)
    tb[TB_HEAD] = head
    tb[TB_RSTEP] = rstep
    tb[TB_RNEXT] = next_other(pitches, nominal)
    tb[TB_RUNS] = np.zeros((n + 2, R_COLS))
    tb[TB_RAUX] = np.zeros(A_COLS)
    p0, tol = float(fp[FP_P0]), float(fp[FP_CLOSURE_TOL])
    runs, aux = tb[TB_RUNS], tb[TB_RAUX]
    delta, _, st = run_close(tab, p0, float(s), float(delta), pitches, n, tol, rstep, tb[TB_RNEXT], runs, aux)
    head[HEAD_LINK_ERROR] = math.nan
    if st == 0:
        xs, zs, two = np.empty(n + 1), np.empty(n + 1), np.empty((n, 2))
        c, e, _ = run_rates(tab, 0.0, runs, aux)
        run_fill(tab, p0, n, delta, 0.0, c, e, runs, aux, xs, zs, two, two.copy(), xs, False)
        head[HEAD_LINK_ERROR] = closure_residual(xs, zs, n, pitches)
    return tuple(tb)
