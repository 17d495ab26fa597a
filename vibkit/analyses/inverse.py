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

from ..model.dynamics import link_multipliers
from ..model.flat_roller import add_flats
from ..model.schema import TensionerOptions, effect_options, gravity_of
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


def inverse_dynamics(model, *, speed, duration, step, start=0.0, effects=None, outputs=(), rollers=(), progress=True):
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
    for j, tj in enumerate(t):
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
