"""Forward dynamics: the motor drives the sprocket, the teeth drive the chain, nothing imposes motion.

The chain is integrated in its independent coordinate s0_1 (roller 1 on the undeformed guide), with
every roller and delta recovered by walking the closure at each evaluation (:mod:`vibkit.chain`),
so the chain is closed to rounding at every step and no stabilisation constant exists. The state
is y = [s0_1, s0dot_1, theta, thetadot, integral of the speed error].
"""

from __future__ import annotations

import math

import numpy as np

from .dynamics import link_multipliers
from .effects import Work, evaluate, pack_parameters
from .integrate import IntegrationError, integrate
from .results import make_dataset

__all__ = ["forward_dynamics", "initial_state", "ForwardModel"]


class ForwardModel:
    """Compiled parameters and scratch arrays of one scene, ready to evaluate and integrate."""

    def __init__(self, model, effects):
        self.model = model
        self.effects = effects
        self.prm = pack_parameters(model, effects)
        self.work = Work(model.n, model.sprocket.teeth)

    def rhs(self, t, y, *, teeth=False):
        dy = np.empty(5)
        st = evaluate(float(t), np.ascontiguousarray(y, dtype=float), dy, self.prm, self.work.arrays, teeth)
        if st != 0:
            raise IntegrationError("the chain could not be closed", t, y)
        return dy

    @property
    def info(self):
        return self.work.arrays[18]


def initial_state(model, *, start=0.0, speed=0.0, theta=None):
    """Closed, meshed initial state: roller 1 at ``start`` [m of undeformed guide], chain speed [m/s].

    The sprocket angle meshes the rollers on the head midway between teeth (no contact), and turns
    with the chain (thetadot = -speed / R^P).
    """
    conf = model.chain.configure(start)
    th = model.meshed_angle(conf) if theta is None else theta
    jac, gam, c, _, _ = model.chain.jacobian(conf)
    # the chain speed is roller 1's speed |J_1| s0dot
    s0dot = speed / math.hypot(*jac[0]) if speed else 0.0
    return np.array([start, s0dot, th, -speed / model.pitch_radius, 0.0]), conf.delta


def forward_dynamics(model, *, duration=None, progress=True, method=None, rtol=None, atol=None, outputs=None,
                     effects=None, t_out=None):
    """Run the forward dynamics of ``model.scene``; see :func:`vibkit.simulate`.

    Keyword arguments override the scene's solver settings, outputs and effects (for benchmarks).
    """
    scene = model.scene
    run = scene.section("run")
    solver = scene.section("solver")
    effects = scene.effects if effects is None else effects
    outputs = scene.outputs["variables"] if outputs is None else outputs
    duration = duration or run["duration"]
    dt = run["output_step"]
    if t_out is None:
        t_out = np.arange(0.0, duration + 0.5 * dt, dt)
    fm = ForwardModel(model, effects)
    y0, d0 = initial_state(model, start=run.get("start", 0.0), speed=run.get("initial_speed", 0.0))
    fm.info[0] = d0
    method = method or solver.get("method", "dopri5")
    rtol = rtol or solver.get("rtol", 1e-7)
    atol = atol or solver.get("atol", 1e-9)
    y_out, stats = integrate(fm.prm, fm.work.arrays, y0, t_out, method=method, rtol=rtol, atol=atol,
                             max_step=solver.get("max_step", math.inf), first_step=solver.get("first_step"),
                             max_wall_time=solver.get("max_wall_time", math.inf), progress=progress)
    return _post_process(fm, t_out, y_out, outputs, stats)


def _post_process(fm, t, y, outputs, stats):
    """Outputs asked for, evaluated at the output states (only those asked for are computed)."""
    model = fm.model
    scene = model.scene
    n = model.n
    nt = t.size
    want = set(outputs)
    need_tension = "link_tension" in want
    need_teeth = bool({"indentation", "contact_force"} & want) and "contact" in fm.effects
    rollers = np.asarray(scene.outputs["rollers"], dtype=int) - 1
    step = scene.outputs["step_accelerometer"]
    need_roller = bool({"roller_position", "roller_velocity", "roller_acceleration"} & want) and rollers.size
    need_accel = "accel_step" in want and step is not None
    ws = fm.work.arrays
    s0a, kk, lam, xs, zs, part, alpha, beta, jac, gam, hacc, eta, sd, fx, fz, cand, ind_t, frc_t, info = ws
    delta = np.empty(nt)
    ddot = np.empty(nt)
    motor = np.empty(nt)
    flank = np.empty((nt, 2))
    resid = np.empty(nt)
    speed = np.empty(nt)
    ke = np.empty(nt)
    pe = np.empty(nt)
    ce = np.empty(nt)
    se = np.empty(nt)
    tension = np.empty((nt, n)) if need_tension else None
    ind = np.empty((nt, model.sprocket.teeth)) if need_teeth else None
    cf = np.empty((nt, model.sprocket.teeth)) if need_teeth else None
    rp = np.empty((nt, rollers.size, 2)) if need_roller else None
    rv = np.empty((nt, rollers.size, 2)) if need_roller else None
    ra = np.empty((nt, rollers.size, 2)) if need_roller else None
    acc_step = np.empty(nt) if need_accel else None
    fp = fm.prm[2]
    g = fp[3] if fm.prm[3][2] else 0.0
    k_s, pre, m_c = fp[11], fp[12], fp[13]
    lam_buf = np.empty(n)
    dy = np.empty(5)
    from .chain import closure_residual

    mid = model.step_rollers(step)[1] if need_accel else 0
    for j in range(nt):
        if not np.all(np.isfinite(y[j])):
            raise IntegrationError("non-finite state in the output", float(t[j]), y[j])
        st = evaluate(float(t[j]), y[j], dy, fm.prm, ws, need_teeth)
        if st != 0:
            raise IntegrationError("the chain could not be closed", float(t[j]), y[j])
        sdot, sddot = y[j, 1], dy[1]
        delta[j], ddot[j], motor[j] = info[0], info[1], info[3]
        flank[j] = info[8], info[9]
        ce[j] = info[5]
        resid[j] = closure_residual(xs, zs, n, model.chain.pitches)
        vx = jac[:, 0] * sdot
        vz = jac[:, 1] * sdot
        speed[j] = math.hypot(vx[0], vz[0])
        ke[j] = 0.5 * float(np.sum(model.mass * (vx * vx + vz * vz))) + 0.5 * m_c * ddot[j] ** 2 \
            + 0.5 * model.sprocket.inertia * y[j, 3] ** 2
        pe[j] = g * float(np.sum(model.mass * zs[:n]))
        se[j] = pre * delta[j] + 0.5 * k_s * delta[j] ** 2
        if need_teeth:
            ind[j] = ind_t
            cf[j] = frc_t
        if need_tension or need_roller or need_accel:
            ax = jac[:, 0] * sddot + hacc[:, 0]
            az = jac[:, 1] * sddot + hacc[:, 1]
            if need_tension:
                resx = model.mass * ax - fx[:n]
                resz = model.mass * az - fz[:n]
                rs_res = part[:n, 2] * resx + part[:n, 3] * resz
                dd2 = info[2]
                f_c = -(pre + k_s * delta[j])
                rd_res = float(np.sum(part[:n, 4] * resx + part[:n, 5] * resz)) + m_c * dd2 - f_c
                link_multipliers(part, xs, zs, n, rs_res, rd_res, 0.0, 0.0, 0.0, lam_buf, False)
                tension[j] = 2.0 * lam_buf * model.chain.pitches
            if need_roller:
                rp[j, :, 0], rp[j, :, 1] = xs[rollers], zs[rollers]
                rv[j, :, 0], rv[j, :, 1] = vx[rollers], vz[rollers]
                ra[j, :, 0], ra[j, :, 1] = ax[rollers], az[rollers]
            if need_accel:
                tx, tz = part[mid, 2], part[mid, 3]
                nrm = math.hypot(tx, tz)
                acc_step[j] = (ax[mid] * tx + az[mid] * tz) / nrm
    data = {}
    simple = {"delta": delta, "delta_dot": ddot, "sprocket_angle": y[:, 2], "sprocket_speed": y[:, 3],
              "motor_torque": motor, "chain_speed": speed, "closure_residual": resid, "s0": y[:, 0]}
    for name, arr in simple.items():
        if name in want:
            data[name] = (("time",), arr)
    if "flank_force" in want:
        data["drive_flank_force"] = (("time",), flank[:, 0])
        data["back_flank_force"] = (("time",), flank[:, 1])
    if "tensioner_displacement" in want:
        data["tensioner_displacement"] = (("time",), delta - delta.mean())
    if need_tension:
        data["link_tension"] = (("time", "link"), tension)
    if need_teeth:
        data["indentation"] = (("time", "tooth"), ind)
        data["contact_force"] = (("time", "tooth"), cf)
    if need_accel:
        data["accel_step"] = (("time",), acc_step)
    if "energy" in want:
        data["kinetic_energy"] = (("time",), ke)
        data["potential_energy"] = (("time",), pe)
        data["contact_energy"] = (("time",), ce)
        data["spring_energy"] = (("time",), se)
    coords = {"time": t}
    if need_tension:
        coords["link"] = np.arange(1, n + 1)
    if need_teeth:
        coords["tooth"] = np.arange(1, model.sprocket.teeth + 1)
    if need_roller:
        coords["roller"] = rollers + 1
        coords["axis"] = ["x", "z"]
        for name, arr in (("roller_position", rp), ("roller_velocity", rv), ("roller_acceleration", ra)):
            if name in want:
                data[name] = (("time", "roller", "axis"), arr)
    nominal = fm.effects.get("motor", {}).get("speed", scene.section("run").get("initial_speed", 0.0))
    attrs = {
        "chain_speed_m_s": float(nominal),
        "link_pass_frequency_hz": model.link_pass_frequency(nominal) if nominal else 0.0,
        "closure_residual_max": float(resid.max()),
        "solver_method": stats["method"],
        "solver_steps": stats["steps"],
        "solver_evaluations": stats["evaluations"],
        "solver_wall_time_s": float(stats["wall_time_s"]),
        "effects": ", ".join(sorted(fm.effects)),
    }
    if step is not None:
        attrs["step_accelerometer"] = int(step)
    return make_dataset(coords, data, attrs, scene)
