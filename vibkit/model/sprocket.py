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

import numba as nb
import numpy as np

from .params import SprocketParams

__all__ = ["tooth_geometry", "tooth_corners", "mesh_phase", "contact_kernel"]


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


@nb.njit(cache=True, error_model="numpy")
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
    loc,
    root_r,
    psi,
    nteeth,
    r_d,
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

    ``radii`` holds each roller's radius [m], ``r_d`` the largest of them (how far a roller reaches).

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
    # each tooth's rotation, theta + psi j, by recurrence from two sines and cosines (not eight per roller)
    cos_t = np.empty(nteeth)
    sin_t = np.empty(nteeth)
    cp, sp = math.cos(psi), math.sin(psi)
    cos_t[0], sin_t[0] = math.cos(theta), math.sin(theta)
    for j in range(1, nteeth):
        cos_t[j] = cos_t[j - 1] * cp - sin_t[j - 1] * sp
        sin_t[j] = sin_t[j - 1] * cp + cos_t[j - 1] * sp
    # the flanks in the tooth's frame: start, direction and 1/length^2 (AB: corners 0-1, DC: 3-2)
    fl = np.empty((2, 5))
    for flank in range(2):
        i0 = 0 if flank == 0 else 3
        i1 = 1 if flank == 0 else 2
        fl[flank, 0] = loc[i0, 0]
        fl[flank, 1] = loc[i0, 1] + root_r
        fl[flank, 2] = loc[i1, 0] - loc[i0, 0]
        fl[flank, 3] = loc[i1, 1] - loc[i0, 1]
        fl[flank, 4] = 1.0 / (fl[flank, 2] ** 2 + fl[flank, 3] ** 2)
    # a circle round each tooth (on its axis) that a roller touching it must reach: teeth farther
    # off are not looked at
    zlo = min(min(loc[0, 1], loc[1, 1]), min(loc[2, 1], loc[3, 1]))
    zhi = max(max(loc[0, 1], loc[1, 1]), max(loc[2, 1], loc[3, 1]))
    zmid = root_r + 0.5 * (zlo + zhi)
    bound = 0.0
    for q in range(4):
        bound = max(bound, math.hypot(loc[q, 0], loc[q, 1] + root_r - zmid))
    bound += r_d
    bound2 = bound * bound
    for jj in range(ncand):
        i = candidates[jj]
        px, pz = xs[i], zs[i]
        dx, dz = px - cx, pz - cz
        phi = math.atan2(-dx, dz)
        rel = phi - theta
        j0 = math.floor(rel / psi)
        for tj in (j0 - 1, j0, j0 + 1, j0 + 2):
            tooth = tj % nteeth
            c, s = cos_t[tooth], sin_t[tooth]
            # the roller's centre in the tooth's frame (x tangential, z radial)
            lx = c * dx + s * dz
            lz = c * dz - s * dx
            if lx * lx + (lz - zmid) * (lz - zmid) >= bound2:
                continue
            for flank in range(2):
                ax, az, ex, ez = fl[flank, 0], fl[flank, 1], fl[flank, 2], fl[flank, 3]
                u = ((lx - ax) * ex + (lz - az) * ez) * fl[flank, 4]
                if u < 0.0:
                    u = 0.0
                elif u > 1.0:
                    u = 1.0
                nlx = lx - (ax + u * ex)
                nlz = lz - (az + u * ez)
                dist = math.sqrt(nlx * nlx + nlz * nlz)
                pen = radii[i] - dist
                if pen <= 0.0 or dist == 0.0:
                    continue
                # back to the world: the normal, and the closest point q on the flank
                nx = c * nlx - s * nlz
                nz = s * nlx + c * nlz
                qx = px - nx
                qz = pz - nz
                nx /= dist
                nz /= dist
                f = k * pen**expo
                energy += k * pen ** (expo + 1.0) / (expo + 1.0)
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
                if flank == 1:
                    f_drive += f
                else:
                    f_back += f
                if want_teeth:
                    if pen > ind_tooth[tooth]:
                        ind_tooth[tooth] = pen
                    force_tooth[tooth] += f
    return torque, energy, worst, active, f_drive, f_back
