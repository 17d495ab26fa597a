"""Drive sprocket: tooth geometry and roller-tooth penalty contact (model.md sections 4-5).

Angles follow the rotation A(theta) of model.md: tooth i points along (-sin theta_i, cos theta_i)
from the centre, theta_i = theta + psi (i - 1), and a point at angle phi sits at
r_C + rho (-sin phi, cos phi). Tooth corners in the tooth frame: A(-B/2, -a), B(-b/2, h),
C(b/2, h), D(B/2, -a) above P_i = r_C + A(theta_i)[0, R^F]. CD is the driving flank when the
sprocket turns clockwise (theta decreasing), AB the back flank.

The contact is elastic: indentation psi = r_d - dist(r, flank segment), normal force
f = k psi^e (1 + 1.5 c_HC psidot) for psi > 0 (Hunt-Crossley damping c_HC, 0 by default). Without
damping the force derives from the potential k psi^(e+1)/(e+1), so the contact conserves energy.
"""

from __future__ import annotations

import math

import numpy as np

from ..runtime.kernel import kernel
from .params import SprocketParams

__all__ = ["tooth_geometry", "tooth_corners", "tooth_table", "mesh_phase", "contact_kernel"]


def tooth_geometry(sp: SprocketParams, link_pitch: float, roller_radius: float) -> dict:
    """Derived tooth quantities: pitch radius, root and tip radii, beta, a, tooth pitch. [m, rad]"""
    rp = sp.pitch_radius(link_pitch)
    rf = rp - roller_radius
    beta = math.atan((sp.base_width / 2.0) / rf)
    return {
        "pitch_radius": rp,
        "root_radius": rf,
        "tip_radius": rp + roller_radius,
        "beta": beta,
        "a": rf * (1.0 - math.cos(beta)),
        "tooth_pitch": 2.0 * math.pi / sp.teeth,
    }


def local_corners(sp: SprocketParams, link_pitch: float, roller_radius: float) -> np.ndarray:
    """Corners A, B, C, D of a tooth in its own frame (x tangential, z radial from the root point). [m]"""
    g = tooth_geometry(sp, link_pitch, roller_radius)
    hb, ht, h, a = sp.base_width / 2.0, sp.tip_width / 2.0, sp.tooth_height, g["a"]
    return np.array([[-hb, -a], [-ht, h], [ht, h], [hb, -a]])


def tooth_corners(sp: SprocketParams, link_pitch: float, roller_radius: float, centre, theta: float) -> np.ndarray:
    """World corners (Z, 4, 2) of every tooth for sprocket angle theta [rad]. [m]"""
    g = tooth_geometry(sp, link_pitch, roller_radius)
    loc = local_corners(sp, link_pitch, roller_radius)
    out = np.empty((sp.teeth, 4, 2))
    for i in range(sp.teeth):
        th = theta + g["tooth_pitch"] * i
        c, s = math.cos(th), math.sin(th)
        for j in range(4):
            lx, lz = loc[j, 0], loc[j, 1] + g["root_radius"]
            out[i, j] = (centre[0] + c * lx - s * lz, centre[1] + s * lx + c * lz)
    return out


def mesh_phase(positions: np.ndarray, centre, sp: SprocketParams, link_pitch: float, radius=None) -> float:
    """Sprocket angle that centres the rollers lying on the pitch circle between teeth. [rad]

    Rollers on the circle of ``radius`` (where they seat on the head; not given: the pitch radius of
    links of ``link_pitch``) are used, else those within a quarter pitch of it; the angle is a
    circular mean of (phi_roller - psi/2) modulo psi, so every such roller sits midway between two teeth.
    """
    rp = sp.pitch_radius(link_pitch) if radius is None else float(radius)
    psi = 2.0 * math.pi / sp.teeth
    d = positions - np.asarray(centre)[None, :]
    rad = np.hypot(d[:, 0], d[:, 1])
    on = np.abs(rad - rp) < 1e-6 * rp + 1e-9
    if not np.any(on):
        on = np.abs(rad - rp) < 0.25 * link_pitch
    if not np.any(on):
        raise ValueError("no roller lies on the sprocket's pitch circle: cannot mesh the sprocket")
    phi = np.arctan2(-d[on, 0], d[on, 1])
    z = np.exp(1j * 2.0 * math.pi * (phi - psi / 2.0) / psi).mean()
    return float(np.angle(z) * psi / (2.0 * math.pi))


# the tooth table (:func:`tooth_table`): rows 0 and 1 the flanks AB and DC in the tooth's frame
# (start x, z; direction x, z; 1 / length^2; unit normal x, z), row 2 the constants, then one row per
# tooth j with cos(psi j), sin(psi j)
T_FLANK_AB, T_FLANK_DC, T_CONST, T_ROT = 0, 1, 2, 3
T_ZMID, T_BOUND2, T_PSI, T_NTEETH, T_WINDOW = 0, 1, 2, 3, 4  # columns of the constants' row
F_AX, F_AZ, F_EX, F_EZ, F_INV, F_NX, F_NZ = 0, 1, 2, 3, 4, 5, 6  # columns of a flank's row
T_COS, T_SIN = 0, 1  # columns of a tooth's row
T_COLS = 7


def tooth_table(loc: np.ndarray, root_r: float, psi: float, nteeth: int, r_d: float) -> np.ndarray:
    """What :func:`contact_kernel` needs of the teeth, computed once per model: each flank in the
    tooth's frame (``loc``: the corners, :func:`local_corners`, above the root point at ``root_r``), a
    circle round each tooth that a roller of radius up to ``r_d`` touching it must reach, each tooth's
    rotation psi j (``psi`` the tooth pitch [rad], ``nteeth`` teeth), and how many teeth beyond the two
    that bracket a roller's angle it can touch (0 unless a roller is wider than the gap between two
    teeth). (nteeth + 3, 7)"""
    loc = np.asarray(loc, dtype=float)
    t = np.zeros((nteeth + T_ROT, T_COLS))
    for row, (i0, i1) in ((T_FLANK_AB, (0, 1)), (T_FLANK_DC, (3, 2))):
        ax, az = loc[i0, 0], loc[i0, 1] + root_r
        ex, ez = loc[i1, 0] - loc[i0, 0], loc[i1, 1] - loc[i0, 1]
        length = math.hypot(ex, ez)
        t[row] = (ax, az, ex, ez, 1.0 / length**2, -ez / length, ex / length)
    zmid = root_r + 0.5 * (loc[:, 1].min() + loc[:, 1].max())
    bound = max(math.hypot(loc[q, 0], loc[q, 1] + root_r - zmid) for q in range(4)) + r_d
    # the widest angle from a tooth's axis at which a roller can touch it: the tooth's half-width at
    # its base seen from the centre, plus the roller's own angular radius there (at least; closer
    # in, a roller would sit inside the sprocket's body), plus more than the fast arctangent's error
    base = root_r + loc[:, 1].min()
    reach = math.atan2(np.abs(loc[:, 0]).max(), base) + math.asin(min(1.0, r_d / base)) + 1e-3
    window = max(0, math.ceil(reach / psi) - 1)
    t[T_CONST, :5] = (zmid, bound * bound, psi, nteeth, window)
    for j in range(nteeth):
        t[T_ROT + j, T_COS] = math.cos(psi * j)
        t[T_ROT + j, T_SIN] = math.sin(psi * j)
    return t


@kernel(inline="always")
def fast_atan2(y, x):
    """atan2(y, x) to 2e-4 rad (a polynomial on one octant, folded): good for choosing teeth (the
    tooth table allows 1e-3 rad for it), not for placing anything."""
    ax, ay = abs(x), abs(y)
    mx = max(ax, ay)
    if mx == 0.0:
        return 0.0
    a = min(ax, ay) / mx
    s = a * a
    r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a
    if ay > ax:
        r = 1.5707963267948966 - r
    if x < 0.0:
        r = 3.141592653589793 - r
    if y < 0.0:
        r = -r
    return r


@kernel()
def contact_kernel(
    xs,
    zs,
    vx,
    vz,
    candidates,
    ncand,
    theta,
    omega,
    cx,
    cz,
    teeth,
    radii,
    k,
    expo,
    damp,
    fx,
    fz,
    ind_tooth,
    force_tooth,
    want_teeth,
):
    """Roller-tooth contact forces for the candidate rollers.

    ``teeth`` is the sprocket's :func:`tooth_table`, ``radii`` each roller's radius [m].

    Adds the contact force on each candidate roller to ``fx, fz`` [N] and returns
    (torque on the sprocket [N m], contact potential energy [J], max indentation [m],
    number of active contacts, sum of normal forces on driving flanks CD [N], the same on back
    flanks AB [N]). With ``want_teeth`` it also fills ``ind_tooth`` (max indentation
    per tooth) [m] and ``force_tooth`` (sum of normal forces per tooth) [N].
    """
    torque = 0.0
    energy = 0.0
    worst = 0.0
    active = 0
    f_drive = 0.0
    f_back = 0.0
    if ncand == 0:
        return torque, energy, worst, active, f_drive, f_back
    zmid, bound2 = teeth[T_CONST, T_ZMID], teeth[T_CONST, T_BOUND2]
    psi, nteeth, window = teeth[T_CONST, T_PSI], int(teeth[T_CONST, T_NTEETH]), int(teeth[T_CONST, T_WINDOW])
    ct, st = math.cos(theta), math.sin(theta)
    for jj in range(ncand):
        i = candidates[jj]
        px, pz = xs[i], zs[i]
        dx, dz = px - cx, pz - cz
        ri = radii[i]
        # the roller's centre in tooth 0's frame (x tangential, z radial), and the teeth on either
        # side of its angle (and ``window`` more each side)
        a = ct * dx + st * dz
        b = ct * dz - st * dx
        j0 = math.floor(fast_atan2(-a, b) / psi)
        tooth = (j0 - window) % nteeth
        for _ in range(2 + 2 * window):
            cj, sj = teeth[T_ROT + tooth, T_COS], teeth[T_ROT + tooth, T_SIN]
            # in this tooth's frame
            lx = cj * a + sj * b
            lz = cj * b - sj * a
            if lx * lx + (lz - zmid) * (lz - zmid) < bound2:
                for flank in range(2):
                    ax, az = teeth[flank, F_AX], teeth[flank, F_AZ]
                    # the distance to the flank's line bounds the distance to the flank
                    dl = (lx - ax) * teeth[flank, F_NX] + (lz - az) * teeth[flank, F_NZ]
                    if dl >= ri or dl <= -ri:
                        continue
                    ex, ez = teeth[flank, F_EX], teeth[flank, F_EZ]
                    u = ((lx - ax) * ex + (lz - az) * ez) * teeth[flank, F_INV]
                    if u < 0.0:
                        u = 0.0
                    elif u > 1.0:
                        u = 1.0
                    nlx = lx - (ax + u * ex)
                    nlz = lz - (az + u * ez)
                    d2 = nlx * nlx + nlz * nlz
                    if d2 >= ri * ri or d2 == 0.0:
                        continue
                    dist = math.sqrt(d2)
                    pen = ri - dist
                    # back to the world: the normal, and the closest point q on the flank
                    c = ct * cj - st * sj
                    s = st * cj + ct * sj
                    nx = c * nlx - s * nlz
                    nz = s * nlx + c * nlz
                    qx = px - nx
                    qz = pz - nz
                    nx /= dist
                    nz /= dist
                    if expo == 1.5:
                        f = k * pen * math.sqrt(pen)
                    else:
                        f = k * pen**expo
                    energy += f * pen / (expo + 1.0)
                    if damp > 0.0:
                        # tooth point velocity: omega x (q - C) = omega (-(qz - cz), qx - cx)
                        tvx = -omega * (qz - cz)
                        tvz = omega * (qx - cx)
                        pendot = -((vx[i] - tvx) * nx + (vz[i] - tvz) * nz)
                        fd = 1.0 + 1.5 * damp * pendot
                        if fd < 0.0:
                            fd = 0.0
                        f *= fd
                    fx[i] += f * nx
                    fz[i] += f * nz
                    # reaction -f n applied at q on the sprocket
                    torque += (qx - cx) * (-f * nz) - (qz - cz) * (-f * nx)
                    if pen > worst:
                        worst = pen
                    active += 1
                    if flank == T_FLANK_DC:
                        f_drive += f
                    else:
                        f_back += f
                    if want_teeth:
                        if pen > ind_tooth[tooth]:
                            ind_tooth[tooth] = pen
                        force_tooth[tooth] += f
            tooth += 1
            if tooth == nteeth:
                tooth = 0
    return torque, energy, worst, active, f_drive, f_back
