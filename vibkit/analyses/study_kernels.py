"""Compiled kernels of the study's formulation (:mod:`vibkit.analyses.reference`): the sparse KKT
system's pattern and values, the roller kinematics in the study's coordinates, and the closure residual.

The applied forces are the forward model's own: the forces on the rollers (gravity, the passengers'
weight by time, rolling resistance: :func:`vibkit.model.effects.roller_forces`), the motor and the
contact candidates come from the shared kernels of :mod:`vibkit.model.effects`, and the contact
forces from :func:`vibkit.model.sprocket.contact_kernel`; parameters are read by named slot
(:mod:`vibkit.model.slots`).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..model.effects import contact_candidates, motor_torque, roller_forces
from ..model.guide import BX, BZ, KAPPA, S0, SIGP, local_map, local_point, locate, point_partials
from ..model.slots import (
    FP_CARRIAGE_MASS,
    FP_CX,
    FP_CZ,
    FP_DAMPING,
    FP_EXPONENT,
    FP_INERTIA,
    FP_KI,
    FP_KP,
    FP_P0,
    FP_PRELOAD,
    FP_ROLLER_RADIUS,
    FP_ROOT_RADIUS,
    FP_SPEED_REF,
    FP_STIFFNESS,
    FP_TENSIONER_STIFFNESS,
    FP_TORQUE_LIMIT,
    IP_CONTACT,
    IP_MOTOR,
    IP_N,
    IP_TENSIONER,
    PART_X,
    PART_XD,
    PART_XDD,
    PART_XS,
    PART_XSD,
    PART_XSS,
    PART_Z,
    PART_ZD,
    PART_ZDD,
    PART_ZS,
    PART_ZSD,
    PART_ZSS,
    PRM_CORNERS,
    PRM_FP,
    PRM_IP,
    PRM_MASS,
    PRM_PASS_ALIGHT,
    PRM_PASS_BOARD,
    PRM_PASS_MASS,
    PRM_PASS_STEP,
    PRM_RADII,
    PRM_TABLE,
    PRM_TEETH,
)
from ..model.sprocket import contact_kernel
from ..runtime.kernel import kernel

__all__ = ["kkt_pattern", "study_partials", "study_kinematics", "assemble", "study_closure_residual"]


@nb.njit(cache=True)
def kkt_pattern(p):
    """Row and column of every non-zero of the KKT matrix, in the order :func:`assemble` fills them."""
    n = p + 2
    nnz = 3 * p + 2 + 6 * p
    rows = np.empty(nnz, dtype=np.int64)
    cols = np.empty(nnz, dtype=np.int64)
    k = 0
    for i in range(p):  # M: diagonal of the rollers and the delta row/column
        rows[k], cols[k] = i, i
        k += 1
        rows[k], cols[k] = i, p
        k += 1
        rows[k], cols[k] = p, i
        k += 1
    rows[k], cols[k] = p, p
    k += 1
    rows[k], cols[k] = p + 1, p + 1
    k += 1
    for j in range(p):  # Phi_q (rows n + j) and its transpose (columns n + j)
        jn = j + 1 if j + 1 < p else 0
        for c in (j, jn, p):
            rows[k], cols[k] = n + j, c
            k += 1
            rows[k], cols[k] = c, n + j
            k += 1
    return rows, cols


@kernel()
def study_partials(tab, k, s0loc, delta, out):
    """r and its partials at s0loc = s0 - s0_k on segment k with the study's *linear* map.

    On a telescopic run (undeformed length Lt) the local arc length is lam = sigma s0loc with
    sigma = (Lt - delta)/Lt (the study's eqs. 4-5 to 4-8 and 5-1, 5-13); on fixed segments lam = s0loc.
    Fills ``out`` (12) with x, z, r_s, r_d, r_ss, r_sd, r_dd (x and z of each), as
    :func:`vibkit.model.guide.point_partials` does for vibkit's own map.
    """
    sigp = tab[k, SIGP]
    sig = 1.0 + sigp * delta
    lam = sig * s0loc
    x, z, phi = local_point(tab, k, lam, delta)
    kap = tab[k, KAPPA]
    tx, tz = math.cos(phi), math.sin(phi)
    nx, nz = -tz, tx
    lam_d = sigp * s0loc
    out[PART_X] = x
    out[PART_Z] = z
    out[PART_XS] = sig * tx
    out[PART_ZS] = sig * tz
    out[PART_XD] = tab[k, BX] + lam_d * tx
    out[PART_ZD] = tab[k, BZ] + lam_d * tz
    out[PART_XSS] = sig * sig * kap * nx
    out[PART_ZSS] = sig * sig * kap * nz
    out[PART_XSD] = sigp * tx + sig * kap * lam_d * nx
    out[PART_ZSD] = sigp * tz + sig * kap * lam_d * nz
    out[PART_XDD] = kap * lam_d * lam_d * nx
    out[PART_ZDD] = kap * lam_d * lam_d * nz


@kernel()
def study_kinematics(tab, p0, q, qd, p, linear, part, vel, wq):
    """Roller positions and partials (part (p, 12)), velocities (vel (p, 2)) and the
    quadratic-velocity accelerations w_i (wq (p, 2)) at coordinates q and rates qd, with the
    study's linear map (``linear``) or vibkit's smooth one (:func:`vibkit.model.guide.local_map`)."""
    delta = q[p]
    ddot = qd[p]
    for i in range(p):
        s0w = q[i] - p0 * math.floor(q[i] / p0)
        k = locate(tab, s0w)
        s0loc = s0w - tab[k, S0]
        if linear:
            study_partials(tab, k, s0loc, delta, part[i])
        else:
            point_partials(tab, k, local_map(tab, k, s0loc, delta)[0], s0loc, delta, part[i])
        sd = qd[i]
        vel[i, 0] = part[i, PART_XS] * sd + part[i, PART_XD] * ddot
        vel[i, 1] = part[i, PART_ZS] * sd + part[i, PART_ZD] * ddot
        wq[i, 0] = part[i, PART_XSS] * sd * sd + 2.0 * part[i, PART_XSD] * sd * ddot + part[i, PART_XDD] * ddot * ddot
        wq[i, 1] = part[i, PART_ZSS] * sd * sd + 2.0 * part[i, PART_ZSD] * sd * ddot + part[i, PART_ZDD] * ddot * ddot


@kernel()
def assemble(t, y, prm, pitches, linear, alpha, beta, ws, data, rhs):
    """Fill the KKT values ``data`` (pattern of :func:`kkt_pattern`) and right-hand side ``rhs``.

    State y = [q (n), qdot (n), integral of the sprocket speed error]. Returns
    (motor torque [N m], contact torque [N m], speed-error rate for the integral state [rad/s]).
    ``ws`` = (part, vel, wq, fx, fz, cand, ind_t, frc_t, xs, zs, vx, vz).
    """
    # the first nine entries of vibkit.model.effects.pack_parameters (later ones, if any, are not needed)
    tab, loc, fp, ip, mass = prm[PRM_TABLE], prm[PRM_CORNERS], prm[PRM_FP], prm[PRM_IP], prm[PRM_MASS]
    pm, ps, pb, pa = prm[PRM_PASS_MASS], prm[PRM_PASS_STEP], prm[PRM_PASS_BOARD], prm[PRM_PASS_ALIGHT]
    part, vel, wq, fx, fz, cand, ind_t, frc_t, xs, zs, vx, vz = ws
    p = ip[IP_N]
    n = p + 2
    p0 = fp[FP_P0]
    q = y[:n]
    qd = y[n : 2 * n]
    study_kinematics(tab, p0, q, qd, p, linear, part, vel, wq)
    for i in range(p):
        xs[i] = part[i, PART_X]
        zs[i] = part[i, PART_Z]
    # applied forces on the rollers
    # StudyFormulation refuses passengers by place: q holds the rollers' s0 all the same
    roller_forces(t, fp, ip, mass, pm, ps, pb, pa, q, vel, 1.0, p, fx, fz)
    torque_c = 0.0
    if ip[IP_CONTACT] == 1:
        # candidates: the rollers whose circle can reach a tooth (centre within root + height + r_d;
        # loc[1, 1] is the height of the tooth's corner B in its own frame)
        reach = fp[FP_ROOT_RADIUS] + loc[1, 1] + fp[FP_ROLLER_RADIUS] + 1e-9
        ncand = contact_candidates(xs, zs, p, fp[FP_CX], fp[FP_CZ], reach, cand)
        for i in range(p):
            vx[i] = vel[i, 0]
            vz[i] = vel[i, 1]
        # the kernel's first return value is the torque on the sprocket (the others are diagnostics)
        torque_c = contact_kernel(
            xs,
            zs,
            vx,
            vz,
            cand,
            ncand,
            y[p + 1],
            y[n + p + 1],
            fp[FP_CX],
            fp[FP_CZ],
            prm[PRM_TEETH],
            prm[PRM_RADII],
            fp[FP_STIFFNESS],
            fp[FP_EXPONENT],
            fp[FP_DAMPING],
            fx,
            fz,
            ind_t,
            frc_t,
            False,
        )[0]
    f_c = 0.0
    m_c = 0.0
    if ip[IP_TENSIONER] == 1:
        f_c = -(fp[FP_PRELOAD] + fp[FP_TENSIONER_STIFFNESS] * q[p])
        m_c = fp[FP_CARRIAGE_MASS]
    motor = 0.0
    derr = 0.0
    if ip[IP_MOTOR] == 1:
        motor, derr = motor_torque(fp[FP_SPEED_REF] - qd[p + 1], y[2 * n], fp[FP_KP], fp[FP_KI], fp[FP_TORQUE_LIMIT])
    # mass matrix and generalised forces Q + Q_v
    k = 0
    mdd = m_c
    qdel = f_c
    for i in range(p):
        rsx, rsz, rdx, rdz = part[i, PART_XS], part[i, PART_ZS], part[i, PART_XD], part[i, PART_ZD]
        gx = fx[i] - mass[i] * wq[i, 0]
        gz = fz[i] - mass[i] * wq[i, 1]
        data[k] = mass[i] * (rsx * rsx + rsz * rsz)
        off = mass[i] * (rsx * rdx + rsz * rdz)
        data[k + 1] = off
        data[k + 2] = off
        k += 3
        mdd += mass[i] * (rdx * rdx + rdz * rdz)
        rhs[i] = rsx * gx + rsz * gz
        qdel += rdx * gx + rdz * gz
    data[k] = mdd
    data[k + 1] = fp[FP_INERTIA]
    k += 2
    rhs[p] = qdel
    rhs[p + 1] = motor + torque_c
    # constraints, their Jacobian, and the Baumgarte-stabilised right-hand side
    b2 = beta * beta
    for j in range(p):
        jn = j + 1 if j + 1 < p else 0
        ux = part[jn, PART_X] - part[j, PART_X]
        uz = part[jn, PART_Z] - part[j, PART_Z]
        dvx = vel[jn, 0] - vel[j, 0]
        dvz = vel[jn, 1] - vel[j, 1]
        c_j = ux * ux + uz * uz - pitches[j] * pitches[j]
        cdot = 2.0 * (ux * dvx + uz * dvz)
        gam = -2.0 * (dvx * dvx + dvz * dvz) - 2.0 * (ux * (wq[jn, 0] - wq[j, 0]) + uz * (wq[jn, 1] - wq[j, 1]))
        a0 = -2.0 * (ux * part[j, PART_XS] + uz * part[j, PART_ZS])
        a1 = 2.0 * (ux * part[jn, PART_XS] + uz * part[jn, PART_ZS])
        ad = 2.0 * (ux * (part[jn, PART_XD] - part[j, PART_XD]) + uz * (part[jn, PART_ZD] - part[j, PART_ZD]))
        data[k] = a0
        data[k + 1] = a0
        data[k + 2] = a1
        data[k + 3] = a1
        data[k + 4] = ad
        data[k + 5] = ad
        k += 6
        rhs[n + j] = gam - 2.0 * alpha * cdot - b2 * c_j
    return motor, torque_c, derr


@kernel()
def study_closure_residual(part, p, pitches):
    """Largest | |r_{i+1} - r_i| - L_i | over the links (the last joins roller p to roller 1). [m]"""
    worst = 0.0
    for i in range(p):
        j = i + 1 if i + 1 < p else 0
        d = abs(math.hypot(part[j, PART_X] - part[i, PART_X], part[j, PART_Z] - part[i, PART_Z]) - pitches[i])
        if d > worst:
            worst = d
    return worst
