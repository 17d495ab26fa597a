"""Inverse dynamics: impose roller 1's arc length s1 = s_start + v t on the deformed guide and the
sprocket angle theta = theta0 + omega t, omega = -2 pi f / Z with f the links' counted rate over the run (the
sprocket in mesh with the chain on average; roller 1 rides the heads at v too, where the chain on the straight runs
slower, so f is below v / L by about 0.04 %); solve positions, velocities, accelerations, link tensions (Lagrange
multipliers, T_j = 2 lambda_j L) and the drag force.

The imposed constraint D = s(s0_1, delta) - s_start - v t involves delta through the telescopic
runs, so its derivatives dD/ds0_1 = sigma and dD/ddelta enter the multiplier solve; the drive force
F = -mu is the force along the deformed guide that drags roller 1, and F v equals the rate of
change of kinetic plus potential energy (there is no friction).
"""

from __future__ import annotations

import math

import numpy as np

from ..model.chain import fill_partials, sensitivity, walk_ghost
from ..model.dynamics import link_multipliers
from ..model.flat_roller import add_flats
from ..model.guide import AX, AZ, BX, BZ, COS0, CUMD, KAPPA, S0, SIGP, SIN0, local_map, locate
from ..model.schema import TensionerOptions, effect_options, gravity_of
from ..runtime.kernel import kernel
from ..runtime.progress import Progress
from .results import counted_speed, make_dataset, output_times

__all__ = ["inverse_dynamics"]


def _solve_s0(model, s_target, s0_guess):
    """Roller 1's s0 such that its deformed arc length is s_target (Newton, exact derivative)."""
    chain = model.chain
    s0 = s0_guess
    for _ in range(30):
        conf = chain.configure(s0)
        s, sig, sd, lss, lsd = chain.s_deformed(s0, conf.delta)
        per = model.guide.p0 - 2.0 * conf.delta
        f = math.remainder(s - s_target, per)
        jac, gam, c, alpha, beta = chain.jacobian(conf)
        dsd = sig + sd * c
        if abs(f) < 1e-13:
            return s0, conf, (sig, sd, c, dsd, lss, lsd)
        s0 -= f / dsd
    raise RuntimeError(f"inverse dynamics: could not place roller 1 at s = {s_target:.9g} m")


@kernel()
def _ieee_remainder(x, y):
    """``math.remainder(x, y)`` for y > 0 (exact, as IEEE 754's: fmod is exact, and so is taking y off a
    remainder in [y / 2, y]); ties go to the even quotient."""
    r = np.fmod(x, y)
    half = 0.5 * y
    if r > half or (r == half and np.fmod(x - r, 2.0 * y) != 0.0):
        r -= y
    elif r < -half or (r == -half and np.fmod(x - r, 2.0 * y) != 0.0):
        r += y
    return r


@kernel()
def _closure_residual(xs, zs, n, pitches):
    """:func:`vibkit.model.chain.closure_residual` (max over the n links of | |r_{i+1} - r_i| - L_i |) with the
    square root of the squares where that takes ``math.hypot`` (a third of the time, the same to rounding of
    the link's length: the chain's scale is metres, far from hypot's overflow). [m]"""
    worst = 0.0
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        dx = xs[j] - xs[i]
        dz = zs[j] - zs[i]
        d = abs(math.sqrt(dx * dx + dz * dz) - pitches[i])
        if d > worst:
            worst = d
    return worst


@kernel()
def _place(tab, p0, s_target, s0, delta):
    """Roller 1's s0 at which its arc length on the guide deformed by ``delta`` is ``s_target`` (mod the loop),
    to |f| < 1e-13 m as :func:`_solve_s0` takes it: Newton's method on the guide's local map, no walk of the
    chain. Returns (s0, converged)."""
    for _ in range(20):
        s0w = s0 - p0 * math.floor(s0 / p0)
        k = locate(tab, s0w)
        lm, sig, _, _, _ = local_map(tab, k, s0w - tab[k, S0], delta)
        f = _ieee_remainder(tab[k, S0] + tab[k, CUMD] * delta + lm - s_target, p0 - 2.0 * delta)
        if abs(f) < 1e-13:
            return s0, True
        s0 -= f / sig
    return s0, False


@kernel()
def _placed_rate(tab, p0, s_target, s0, delta):
    """d s0_1 / d delta of roller 1 placed by :func:`_place` (its arc length on the deformed guide held at
    ``s_target`` mod the loop P0 - 2 delta while delta moves), at roller 1's ``s0``."""
    s0w = s0 - p0 * math.floor(s0 / p0)
    k = locate(tab, s0w)
    lm, sig, lmd, _, _ = local_map(tab, k, s0w - tab[k, S0], delta)
    per = p0 - 2.0 * delta
    gap = tab[k, S0] + tab[k, CUMD] * delta + lm - s_target
    loops = round((gap - _ieee_remainder(gap, per)) / per)  # the loops between s_target and roller 1
    return -(tab[k, CUMD] + lmd + 2.0 * loops) / sig


@kernel()
def _closure_slope(tab, p0, s_target, s0, kk, xs, zs, delta, n):
    """dh/ddelta of the ghost residual h of the walk just made (points ``s0``, ``kk``, ``xs``, ``zs``, n links)
    with roller 1 placed at ``s_target`` on the guide that delta deforms: the sensitivity recursion of
    :func:`vibkit.model.chain.sensitivity` (alpha = d s0_i / d s0_1, beta = d s0_i / d delta) in one pass with
    no partials stored, each point's dr/ds0 and dr/ddelta as :func:`vibkit.model.guide.point_partials` has
    them but an arc's tangent from the point's radius (t = kappa (-(z - c_z), x - c_x), c its centre) instead of
    the sine and cosine of its angle; then h = s0_ghost - s0_1 - P0 along roller 1's placement:
    dh/ddelta = beta_ghost + (alpha_ghost - 1) d s0_1 / d delta."""
    alpha, beta = 1.0, 0.0
    seg = -1  # the segment whose constants are below
    kap = tx0 = tz0 = bx = bz = cx = cz = 0.0
    tele = False
    psx = psz = pdx = pdz = 0.0
    for i in range(n + 1):
        k = kk[i]
        if k != seg:
            seg = k
            kap, tx0, tz0, bx, bz = tab[k, KAPPA], tab[k, COS0], tab[k, SIN0], tab[k, BX], tab[k, BZ]
            tele = tab[k, SIGP] != 0.0
            if kap != 0.0:
                cx = tab[k, AX] + bx * delta - tz0 / kap
                cz = tab[k, AZ] + bz * delta + tx0 / kap
        tx, tz = tx0, tz0
        if kap != 0.0:
            tx, tz = -kap * (zs[i] - cz), kap * (xs[i] - cx)
        ls, ld = 1.0, 0.0
        if tele:
            s0loc = s0[i] - p0 * math.floor(s0[i] / p0) - tab[k, S0]
            if s0loc < -1e-9:  # point found a hair before its segment's start across the wrap
                s0loc += p0
            _, ls, ld, _, _ = local_map(tab, k, s0loc, delta)
        rsx, rsz, rdx, rdz = ls * tx, ls * tz, bx + ld * tx, bz + ld * tz
        if i > 0:
            ux = xs[i] - xs[i - 1]
            uz = zs[i] - zs[i - 1]
            inv = 1.0 / (ux * rsx + uz * rsz)
            ratio = (ux * psx + uz * psz) * inv  # d s0_i+1 / d s0_i along the link
            rise = (ux * (pdx - rdx) + uz * (pdz - rdz)) * inv  # d s0_i+1 / d delta at fixed s0_i
            alpha = ratio * alpha
            beta = ratio * beta + rise
        psx, psz, pdx, pdz = rsx, rsz, rdx, rdz
    return beta + (alpha - 1.0) * _placed_rate(tab, p0, s_target, s0[0], delta)


@kernel()
def inverse_positions(
    tab,
    p0,
    lt,
    pitches,
    n,
    tol,
    start,
    speed,
    t,
    j0,
    s0,
    delta,
    ridx,
    s0_1,
    deltas,
    resid,
    rpos,
    rs0,
    scratch,
    kk,
    part,
):
    """The position-only inverse run in one compiled loop: samples ``j0``, ``j0 + 1``, ... of the times ``t``,
    from roller 1 at ``s0`` and the closure's guess ``delta``.

    The two conditions of a sample are those of the Python loop (:func:`_solve_s0` and
    :meth:`vibkit.model.chain.Chain.configure`), to the same tolerances: roller 1 at its arc length
    ``start + speed t`` on the deformed guide (|f| < 1e-13 m), and the chain closed (the ghost residual
    |h| <= tol, or a step below delta's rounding with |h| < 1e3 tol, as solve_closure takes it). They are
    solved the other way round: for a trial delta roller 1 is placed on the guide that delta deforms (the guide's
    local map only: :func:`_place`), and one walk of the chain from there gives h. Each sample starts on the
    parabola through the last three; its first step is Newton's, with dh/ddelta of that walk along roller 1's
    placement (:func:`_closure_slope`: one pass, no trigonometry, under half a walk), any further step along the
    secant of h. A sample takes two walks where the Python loop's Newton steps take six walks and three sets of
    partial derivatives (a slope carried from the sample before, off by about 1e-4 of itself, took three); the
    walks after the first leave out the telescopic runs' s0 (:func:`vibkit.model.chain.walk_ghost`) unless rollers
    ``ridx`` are asked for.
    The numbers differ from the Python loop's within those tolerances (the iterations end elsewhere inside
    them).

    Fills ``s0_1``, ``deltas``, ``resid`` and, for the rollers ``ridx`` (from 0), ``rpos`` and ``rs0``;
    ``scratch`` (6, n + 1), ``kk`` (n + 1,), ``part`` (n + 1, 12) are work arrays. Returns (the first sample
    not done, roller 1's s0 and the closure's guess there): a sample whose placement or closure fails here
    is left to the Python loop, which takes it up from there and says why."""
    sw, lam, xs, zs, alpha, beta = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5]
    slope = 0.0  # dh/ddelta along the placed roller 1
    eps8 = 8.0 * 2.220446049250313e-16
    for j in range(j0, t.size):
        s_target = start + speed * t[j]
        s0_j, delta_j = s0, delta  # where the Python loop takes the sample up again, should it fail here
        if j >= j0 + 3:  # on the parabola through the last three
            s0 = 3.0 * (s0_1[j - 1] - s0_1[j - 2]) + s0_1[j - 3]
            delta = 3.0 * (deltas[j - 1] - deltas[j - 2]) + deltas[j - 3]
        ok = False
        g_prev = h_prev = 0.0
        for it in range(30):
            s0, placed = _place(tab, p0, s_target, s0, delta)
            if not placed:
                return j, s0_j, delta_j
            # the first walk whole (the slope's pass reads its runs' s0), the others for h and the positions (and the
            # s0 of the rollers asked for)
            whole = it == 0 or ridx.size > 0
            h = walk_ghost(tab, p0, s0, delta, pitches, n, sw, kk, lam, xs, zs, 1.0 if whole else 0.0)
            if math.isnan(h):
                return j, s0_j, delta_j
            if abs(h) <= tol:
                ok = True
                break
            if it == 0:
                slope = _closure_slope(tab, p0, s_target, sw, kk, xs, zs, delta, n)
            elif abs(h - h_prev) > 1e3 * tol:
                sec = (h - h_prev) / (delta - g_prev)  # where h changed by well over its rounding
                if 0.25 * slope < sec < 4.0 * slope:
                    slope = sec
            if not slope > 0.0 or it == 10:
                if not whole:  # the same walk again, its runs' s0 too
                    walk_ghost(tab, p0, s0, delta, pitches, n, sw, kk, lam, xs, zs, 1.0)
                fill_partials(tab, p0, sw, kk, lam, delta, n + 1, part)
                sensitivity(part, xs, zs, n + 1, alpha, beta)
                slope = beta[n]
                if not slope > 0.0:
                    return j, s0_j, delta_j
            step = -h / slope
            if abs(step) <= eps8 * max(abs(delta), 1e-3) and abs(h) < 1e3 * tol:
                ok = True  # stalled at the resolution of delta: rounding keeps |h| just above tol
                break
            g_prev, h_prev = delta, h
            delta += step
        if not ok:
            return j, s0_j, delta_j
        s0_1[j] = s0
        deltas[j] = delta
        resid[j] = _closure_residual(xs, zs, n, pitches)
        for i in range(ridx.size):
            r = ridx[i]
            rpos[j, i, 0] = xs[r]
            rpos[j, i, 1] = zs[r]
            rs0[j, i] = sw[r]
    return t.size, s0, delta


class _Positions:
    """The compiled loop of a position-only inverse run (:func:`inverse_positions`) with its work arrays."""

    def __init__(self, model, start, speed, t, ridx, s0_1, out, rpos, rs0):
        chain = model.chain
        n = chain.n
        self.chain, self.start, self.speed, self.t = chain, float(start), float(speed), t
        self.ridx = np.ascontiguousarray(ridx, dtype=np.int64)
        self.s0_1, self.delta, self.resid, self.rpos, self.rs0 = s0_1, out["delta"], out["closure_residual"], rpos, rs0
        self.scratch = np.empty((6, n + 1))
        self.kk = np.empty(n + 1, dtype=np.int64)
        self.part = np.empty((n + 1, 12))

    def run(self, j, s0):
        """Samples from ``j`` on, roller 1 at ``s0`` to start from; returns (the first not done, roller 1's s0)."""
        chain, g = self.chain, self.chain.guide
        model_lt = g.params.tensioner_length
        done, s0, delta = inverse_positions(
            g.table,
            g.p0,
            model_lt,
            chain.pitches,
            chain.n,
            chain.tol,
            self.start,
            self.speed,
            self.t,
            j,
            float(s0),
            float(chain._delta_guess),
            self.ridx,
            self.s0_1,
            self.delta,
            self.resid,
            self.rpos,
            self.rs0,
            self.scratch,
            self.kk,
            self.part,
        )
        chain._delta_guess = float(delta)  # the closure's guess where the Python loop goes on
        return int(done), float(s0)


def inverse_dynamics(
    model, *, speed, duration, step, start=0.0, effects=None, outputs=(), rollers=(), progress=True, compiled=True
):
    """Run the inverse dynamics; see module docstring.

    Parameters
    ----------
    model : EscalatorModel
    speed : float
        Imposed speed of roller 1 along the deformed guide. [m/s]
    duration, step : float
        Length of the run and time step of the output. [s]
    start : float
        s1 at t = 0. [m]
    effects : dict
        ``gravity`` and ``passengers`` as in the scene (others are rejected at scene load).
    outputs : sequence of str
        Names from :data:`vibkit.model.scene.OUTPUTS` ``["inverse"]``.
    compiled : bool
        Outputs of the chain's positions only (no rates or forces): solve the samples in one compiled loop
        (:func:`inverse_positions`: the same tolerances as the Python loop, its numbers within them, many times
        faster); False: the Python loop.

    Returns
    -------
    xarray.Dataset with dimension ``time``.
    """
    effects = effect_options(effects)
    n = model.n
    t = output_times(duration, step, "motion.step")
    g = effects["gravity"].g if "gravity" in effects else 0.0
    # no tensioner effect: the carriage of the tensioner options' defaults (no spring, no mass)
    tens = effects["tensioner"] if "tensioner" in effects else TensionerOptions()
    k_s, pre, m_c = tens.stiffness, tens.preload, tens.mass
    want = set(outputs) | {"delta"}
    # what has to be computed for what was asked: positions always; motion for rates and forces
    need_motion = bool(want - {"delta", "closure_residual", "sprocket_angle", "sprocket_speed", "roller_position"})
    need_forces = bool(want & {"link_tension", "drive_force", "energy"})
    ridx = np.asarray(rollers, dtype=int) - 1
    nt = t.size
    out = {
        name: np.full(nt, np.nan)
        for name in (
            "delta",
            "delta_dot",
            "delta_ddot",
            "drive_force",
            "closure_residual",
            "chain_speed",
            "kinetic_energy",
            "potential_energy",
            "power_balance",
            "spring_energy",
        )
    }
    tension = np.empty((nt, n))
    rpos = np.empty((nt, ridx.size, 2))
    rvel = np.empty((nt, ridx.size, 2))
    racc = np.empty((nt, ridx.size, 2))
    rs0 = np.empty((nt, ridx.size))
    omega = model.sprocket_speed(speed)
    s0_1 = np.empty(nt)  # roller 1's undeformed coordinate: the links passed, for the link pass stated
    s0 = float(model.guide.s_to_s0(start, 0.0))
    schedule = model.passenger_schedule(effects["passengers"], s0) if "passengers" in effects else None
    lam = np.empty(n)
    scratch = np.empty(n)
    theta0 = None
    bar = Progress(nt, "inverse dynamics", enabled=progress)
    compiled = None if need_motion or not compiled else _Positions(model, start, speed, t, ridx, s0_1, out, rpos, rs0)
    done = 0  # samples the compiled loop has done
    for j, tj in enumerate(t):
        if j < done:
            continue
        if compiled is not None and theta0 is not None:
            # positions only: the samples from here in one compiled loop, to the end or to one it leaves to this loop
            done, s0 = compiled.run(j, s0)
            bar.update(done)
            if done == nt:
                break  # every sample done (not 1.5 ms of skipping the rest one by one)
            if j < done:
                continue
        s_target = start + speed * tj
        s0, conf, (sig, sd, c, dsd, lss, lsd) = _solve_s0(model, s_target, s0)
        s0_1[j] = s0
        if theta0 is None:
            theta0 = model.meshed_angle(conf)
        out["delta"][j] = conf.delta
        out["closure_residual"][j] = conf.closure_residual
        if ridx.size:
            rpos[j] = conf.position[ridx]
            rs0[j] = conf.s0[ridx]
        if not need_motion:
            bar.update(j + 1)
            continue
        s0dot = speed / dsd
        # the imposed s(s0_1, delta) = s_start + v t differentiated twice:
        # sig s0dd + sd deltadd + lss s0d^2 + 2 lsd s0d deltad = 0, with deltadd = c s0dd + e
        mo = model.chain.motion(conf, s0dot, 0.0)
        e = mo["e"]
        ddot = c * s0dot
        s0ddot = -(sd * e + lss * s0dot**2 + 2.0 * lsd * s0dot * ddot) / dsd
        mo = model.chain.motion(conf, s0dot, s0ddot)
        vel, acc = mo["velocity"], mo["acceleration"]
        dd = mo["delta_ddot"]
        out["delta_dot"][j] = mo["delta_dot"]
        out["delta_ddot"][j] = dd
        out["chain_speed"][j] = math.hypot(*vel[0])
        if ridx.size:
            rvel[j] = vel[ridx]
            racc[j] = acc[ridx]
        if not need_forces:
            bar.update(j + 1)
            continue
        fx = np.zeros(n)
        fz = -model.mass * g
        if "passengers" in effects:
            model.passenger_forces(effects["passengers"], tj, gravity_of(effects), fz, s0=conf.s0, schedule=schedule)
        resx = model.mass * acc[:, 0] - fx
        resz = model.mass * acc[:, 1] - fz
        part = conf.partials
        rs_res = part[:, 2] * resx + part[:, 3] * resz
        f_c = -(pre + k_s * conf.delta)
        rd_res = float(np.sum(part[:, 4] * resx + part[:, 5] * resz)) + m_c * dd - f_c
        xs, zs = conf.position[:, 0].copy(), conf.position[:, 1].copy()
        mu, _ = link_multipliers(part, xs, zs, n, rs_res, rd_res, 0.0, sig, sd, lam, True, scratch)
        tension[j] = 2.0 * lam * model.chain.pitches
        out["drive_force"][j] = -mu
        out["kinetic_energy"][j] = (
            0.5 * float(np.sum(model.mass * (vel**2).sum(axis=1)))
            + 0.5 * m_c * mo["delta_dot"] ** 2
            + 0.5 * model.sprocket.inertia * omega**2
        )
        out["potential_energy"][j] = g * float(np.sum(model.mass * conf.position[:, 1]))
        out["spring_energy"][j] = pre * conf.delta + 0.5 * k_s * conf.delta**2
        # exact rate of change of energy, for the power balance: sum m v.a + m g v_z + carriage terms
        dEdt = (
            float(np.sum(model.mass * (vel * acc).sum(axis=1)))
            + g * float(np.sum(model.mass * vel[:, 1]))
            + (m_c * dd + pre + k_s * conf.delta) * mo["delta_dot"]
        )
        out["power_balance"][j] = -mu * speed - dEdt
        bar.update(j + 1)
    bar.close()
    # roller 1 runs at the imposed speed along the guide, heads included: the chain on the straight, whose speed
    # the link pass counts, runs slower while roller 1 rides a head (0.037 % over a loop of the study's chain);
    # the sprocket turns at the links' counted rate, so that it stays in mesh with the chain on average
    chain_speed, f_lp, _ = counted_speed(model, t, s0_1, speed, speed_hint=speed)  # signed: the way it runs
    meshed = math.copysign(2.0 * math.pi * f_lp / model.sprocket.teeth, omega) if f_lp > 0 else omega
    out["kinetic_energy"] += 0.5 * model.sprocket.inertia * (meshed**2 - omega**2)  # a constant, as before
    omega = meshed
    data = {}
    for name in ("delta", "delta_dot", "delta_ddot", "drive_force", "closure_residual", "chain_speed"):
        if name in want:
            data[name] = (("time",), out[name])
    if "link_tension" in want:
        data["link_tension"] = (("time", "link"), tension)
    if "sprocket_angle" in want:
        data["sprocket_angle"] = (("time",), theta0 + omega * t)
    if "sprocket_speed" in want:
        data["sprocket_speed"] = (("time",), np.full(nt, omega))
    if "energy" in want:
        data["kinetic_energy"] = (("time",), out["kinetic_energy"])
        data["potential_energy"] = (("time",), out["potential_energy"])
        if k_s or pre:
            data["spring_energy"] = (("time",), out["spring_energy"])
    coords = {"time": t}
    if "link_tension" in want:
        coords["link"] = np.arange(1, n + 1)
    if ridx.size and any(v.startswith("roller_") for v in want):
        motion = (rvel, racc) if need_motion else (None, None)
        add_flats(model, t, rs0, out["delta"], ridx, rpos, *motion)
        coords["roller"] = np.asarray(rollers)
        coords["axis"] = ["x", "z"]
        for name, arr in (("roller_position", rpos), ("roller_velocity", rvel), ("roller_acceleration", racc)):
            if name in want:
                data[name] = (("time", "roller", "axis"), arr)
    attrs = {
        "chain_speed_m_s": chain_speed,
        "speed_set_point_m_s": float(speed),  # imposed on roller 1, along the guide
        "closure_residual_max": float(out["closure_residual"].max()),
        "closure_residual_max_units": "m",
        "power_balance_max_W": float(np.abs(out["power_balance"]).max()) if need_forces else float("nan"),
        "link_pass_frequency_hz": f_lp,
    }
    ds = make_dataset(coords, data, attrs, model.scene)
    return ds
