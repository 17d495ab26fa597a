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
    return {"pitch_radius": rp, "root_radius": rf, "tip_radius": rp + roller_radius, "beta": beta,
            "a": rf * (1.0 - math.cos(beta)), "tooth_pitch": 2.0 * math.pi / sp.teeth}


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


def mesh_phase(positions: np.ndarray, centre, sp: SprocketParams, link_pitch: float) -> float:
    """Sprocket angle that centres the rollers lying on the pitch circle between teeth. [rad]

    Rollers within half a pitch of the pitch circle are used; the angle is a circular mean of
    (phi_roller - psi/2) modulo psi, so every such roller sits midway between two teeth.
    """
    rp = sp.pitch_radius(link_pitch)
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
def _segment_closest(px, pz, ax, az, bx, bz):
    ex, ez = bx - ax, bz - az
    t = ((px - ax) * ex + (pz - az) * ez) / (ex * ex + ez * ez)
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    return ax + t * ex, az + t * ez


@nb.njit(cache=True, error_model="numpy")
def contact_kernel(xs, zs, vx, vz, candidates, ncand, theta, omega, cx, cz, loc, root_r, psi, nteeth,
                   r_d, k, expo, damp, fx, fz, ind_tooth, force_tooth, want_teeth):
    """Roller-tooth contact forces for the candidate rollers.

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
    for jj in range(ncand):
        i = candidates[jj]
        px, pz = xs[i], zs[i]
        dx, dz = px - cx, pz - cz
        phi = math.atan2(-dx, dz)
        rel = phi - theta
        j0 = math.floor(rel / psi)
        for tj in (j0 - 1, j0, j0 + 1, j0 + 2):
            th = theta + psi * tj
            c, s = math.cos(th), math.sin(th)
            tooth = tj % nteeth
            for flank in range(2):
                # AB (flank 0: corners 0,1) and DC (flank 1: corners 3,2)
                i0 = 0 if flank == 0 else 3
                i1 = 1 if flank == 0 else 2
                l0x, l0z = loc[i0, 0], loc[i0, 1] + root_r
                l1x, l1z = loc[i1, 0], loc[i1, 1] + root_r
                ax = cx + c * l0x - s * l0z
                az = cz + s * l0x + c * l0z
                bx = cx + c * l1x - s * l1z
                bz = cz + s * l1x + c * l1z
                qx, qz = _segment_closest(px, pz, ax, az, bx, bz)
                nx, nz = px - qx, pz - qz
                dist = math.sqrt(nx * nx + nz * nz)
                pen = r_d - dist
                if pen <= 0.0 or dist == 0.0:
                    continue
                nx /= dist
                nz /= dist
                f = k * pen ** expo
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
