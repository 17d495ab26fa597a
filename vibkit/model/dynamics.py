"""Equations of motion of the chain in its independent coordinate, and the link tensions.

The chain has two degrees of freedom: roller 1's undeformed-guide coordinate s0_1 (every roller
position and delta follow from the closure, :mod:`vibkit.model.chain`) and the sprocket angle theta.
With r_i = r_i(s0_1), v_i = J_i sdot and a_i = J_i sddot + h_i, the virtual power of the chain gives
the one-row equation

    (sum_i m_i J_i.J_i + m_c c^2) sddot = sum_i J_i.(F_i - m_i h_i) + c (F_c - m_c e)

where c = d delta / d s0_1, deltaddot = c sddot + e, m_c the carriage mass and F_c the force on the
carriage along delta. The sprocket obeys I thetaddot = M_motor + M_contact.

Link tensions are the Lagrange multipliers of the closure constraints C_j = |r_{j+1} - r_j|^2 - L^2
(T_j = 2 lambda_j L): the equation of each roller's coordinate involves only the two links it joins,
so the multipliers follow from a cyclic bidiagonal recursion (O(p)) closed by the carriage equation.
"""

from __future__ import annotations

from ..runtime.kernel import kernel
from .slots import PART_XD, PART_XS, PART_ZD, PART_ZS

__all__ = ["link_multipliers", "reduced_equation"]


@kernel()
def link_multipliers(part, xs, zs, n, rs_res, rd_res, q_delta, drive_s, drive_d, lam, with_drive, scratch):
    """Multipliers lambda_j of the closure constraints (fills ``lam`` (n,); ``scratch`` (n,) is work space).

    Parameters
    ----------
    part : (n, 12) partial derivatives of each roller's position (guide.point_partials).
    xs, zs : roller positions. [m]
    rs_res : (n,) r_s,i . (m_i a_i - F_i), the inertia-minus-applied residual along each coordinate. [N]
    rd_res : float, sum_i r_d,i . (m_i a_i - F_i) + m_c deltaddot - F_c. [N]
    q_delta : unused placeholder kept at 0.0 (carriage terms are folded into rd_res).
    drive_s, drive_d : derivatives of an imposed-motion constraint D(s0_1, delta) (inverse dynamics).
    with_drive : bool; when True also solve for the drive multiplier mu and return it.
    scratch : (n,) work space (the recursion's second coefficients).

    Returns
    -------
    mu : float
        The drive multiplier (0 without drive); the power the drive puts in is -mu dD/dt.
    residual : float
        Without drive, the residual of roller 1's equation (a consistency check). [N]
    """
    # lam_j = a_j + b_j lam_0: a_j kept in lam until lam_0 is known, b_j in scratch
    a = lam
    b = scratch
    a[0] = 0.0
    b[0] = 1.0
    for i in range(1, n):
        ux0 = xs[i] - xs[i - 1]
        uz0 = zs[i] - zs[i - 1]
        j = i + 1 if i + 1 < n else 0
        ux1 = xs[j] - xs[i]
        uz1 = zs[j] - zs[i]
        cin = 2.0 * (ux0 * part[i, PART_XS] + uz0 * part[i, PART_ZS])
        cout = 2.0 * (ux1 * part[i, PART_XS] + uz1 * part[i, PART_ZS])
        a[i] = (rs_res[i] + a[i - 1] * cin) / cout
        b[i] = b[i - 1] * cin / cout
    # roller 1's equation: rs_res[0] + lam_{n-1} 2 u_{n-1}.r_s,0 - lam_0 2 u_0.r_s,0 + mu drive_s = 0
    ux = xs[0] - xs[n - 1]
    uz = zs[0] - zs[n - 1]
    cin0 = 2.0 * (ux * part[0, PART_XS] + uz * part[0, PART_ZS])
    cout0 = 2.0 * ((xs[1] - xs[0]) * part[0, PART_XS] + (zs[1] - zs[0]) * part[0, PART_ZS])
    e0_const = rs_res[0] + a[n - 1] * cin0
    e0_lam = b[n - 1] * cin0 - cout0
    # carriage equation: rd_res + sum_j lam_j 2 u_j.(r_d,j+1 - r_d,j) + mu drive_d = 0
    d_const = rd_res + q_delta
    d_lam = 0.0
    for jj in range(n):
        k = jj + 1 if jj + 1 < n else 0
        ux = xs[k] - xs[jj]
        uz = zs[k] - zs[jj]
        w = 2.0 * (ux * (part[k, PART_XD] - part[jj, PART_XD]) + uz * (part[k, PART_ZD] - part[jj, PART_ZD]))
        d_const += a[jj] * w
        d_lam += b[jj] * w
    mu = 0.0
    residual = 0.0
    if with_drive:
        det = e0_lam * drive_d - d_lam * drive_s
        lam0 = (-e0_const * drive_d + d_const * drive_s) / det
        mu = -(e0_const + e0_lam * lam0) / drive_s
    else:
        lam0 = -d_const / d_lam
        residual = e0_const + e0_lam * lam0
    for i in range(n):
        lam[i] += b[i] * lam0
    return mu, residual


@kernel()
def reduced_equation(jac, hacc, fx, fz, mass, c, e, m_c, f_c):
    """Generalised mass and force of the chain's coordinate s0_1 (see module docstring)."""
    m_eff = m_c * c * c
    q = c * (f_c - m_c * e)
    for i in range(jac.shape[0]):
        m_eff += mass[i] * (jac[i, 0] * jac[i, 0] + jac[i, 1] * jac[i, 1])
        q += jac[i, 0] * (fx[i] - mass[i] * hacc[i, 0]) + jac[i, 1] * (fz[i] - mass[i] * hacc[i, 1])
    return m_eff, q
