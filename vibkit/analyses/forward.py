"""Forward dynamics: the motor drives the sprocket, the teeth drive the chain, nothing imposes motion.

The chain is integrated in its independent coordinate s0_1 (roller 1 on the undeformed guide), with
every roller and delta recovered by walking the closure at each evaluation (:mod:`vibkit.model.chain`),
so the chain is closed to rounding at every step and no stabilisation constant exists. The state
is y = [s0_1, s0dot_1, theta, thetadot, integral of the speed error].
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from ..model.chain import close_with_slope, closure_residual
from ..model.dynamics import link_multipliers
from ..model.effects import (
    Work,
    clear_teeth,
    contact_candidates,
    evaluate,
    motor_torque,
    pack_parameters,
    reset_closure,
    sprocket_contact,
)
from ..model.flat_roller import add_flats
from ..model.pitch_table import empty_table, rhs, table_applies, table_delta, table_spacing
from ..model.runs_rhs import build_runs, runs_observe
from ..model.schema import SceneError, effect_options, nominal_speed
from ..model.slots import (
    FP_CARRIAGE_MASS,
    FP_CLOSURE_TOL,
    FP_CX,
    FP_CZ,
    FP_G,
    FP_KI,
    FP_KP,
    FP_LT,
    FP_P0,
    FP_PRELOAD,
    FP_REACH,
    FP_SPEED_REF,
    FP_TENSIONER_STIFFNESS,
    FP_TORQUE_LIMIT,
    HEAD_LINK_ERROR,
    HEAD_RUNS,
    INFO_AT,
    INFO_CURVATURE,
    INFO_DELTA,
    INFO_DELTA_DDOT,
    INFO_DELTA_DOT,
    INFO_ENERGY_C,
    INFO_F_BACK,
    INFO_F_DRIVE,
    INFO_MOTOR,
    INFO_SLOPE,
    INFO_WORST,
    IP_GRAVITY,
    IP_MOTOR,
    IP_PASSENGERS,
    PART_XD,
    PART_XS,
    PART_ZD,
    PART_ZS,
    PASSENGERS_BY_PLACE,
    PRM_FP,
    PRM_IP,
    PRM_MASS,
    PRM_PASS_ALIGHT,
    PRM_PASS_BOARD,
    PRM_PASS_STEP,
    PRM_PITCHES,
    PRM_TABLE,
    TB_HEAD,
    TB_SB,
    WS_INFO,
)
from ..model.table_check import checked_table
from ..runtime.kernel import kernel
from .integrate import IntegrationError, integrate
from .results import counted_speed, make_dataset, output_times

__all__ = ["forward_dynamics", "initial_state", "ForwardModel", "default_rtol"]


class ForwardModel:
    """Compiled parameters and scratch arrays of one scene, ready to evaluate and integrate."""

    def __init__(self, model, effects, *, start=0.0):
        self.model = model
        self.effects = effect_options(effects)
        self.prm = pack_parameters(model, effects, start=start)
        self.work = Work(model.n, model.sprocket.teeth)

    def rhs(self, t, y, *, teeth=False):
        dy = np.empty(5)
        st = evaluate(float(t), np.ascontiguousarray(y, dtype=float), dy, self.prm, self.work.arrays, teeth)
        if st != 0:
            raise IntegrationError("the chain could not be closed", t, y)
        return dy

    @property
    def info(self):
        return self.work.arrays[WS_INFO]


def initial_state(model, *, start=0.0, speed=0.0, theta=None, torque=0.0, ki=0.0, contact=None):
    """Closed, meshed initial state: roller 1 at ``start`` [m of undeformed guide], chain speed [m/s].

    The sprocket angle meshes the rollers on the head midway between teeth (no contact), and turns
    with the chain (thetadot = -2 pi speed / (Z L), :meth:`EscalatorModel.sprocket_speed`).

    A start in steady running against a load (``torque`` [N m] in the sprocket's sense, the motor's
    ``effects.motor.initial_torque``; ``ki`` its integral gain; ``contact`` the scene's contact options): the
    controller's integral starts at torque / ki, and the sprocket turns from the meshed angle towards that
    torque until its teeth, pressed into the rollers, carry it (:meth:`EscalatorModel.loaded_angle`), so that
    the drive holds the chain at once instead of its teeth striking the chain after it has slowed in the backlash.
    """
    conf = model.chain.configure(start)
    th = model.meshed_angle(conf) if theta is None else theta
    integral = 0.0
    if torque != 0.0 and ki > 0.0:
        integral = torque / ki
        if contact is not None:
            th = model.loaded_angle(conf, th, torque, contact.stiffness, contact.exponent)
    jac, gam, c, _, _ = model.chain.jacobian(conf)
    # the chain speed is roller 1's speed |J_1| s0dot
    s0dot = speed / math.hypot(*jac[0]) if speed else 0.0
    return np.array([start, s0dot, th, model.sprocket_speed(speed), integral]), conf.delta


SEAT_TOLERANCE = 1e-9  # [m] a roller this far inside a tooth at t = 0 is refused (the meshed start has none)


def check_seated(fm, y0, d0):
    """Refuse a start with a roller inside a tooth: the contact would fling it out, and the run would not
    be of the escalator meant. Either the head is not where this chain seats on these teeth (a guide head
    radius of another chain), or the rollers and teeth do not fit the pitch (a roller too large for the
    gap between two teeth); the message names the keys of the cause."""
    if "contact" not in fm.effects:
        return
    reset_closure(fm.info, d0)
    fm.rhs(0.0, y0)
    worst = float(fm.info[INFO_WORST])
    if worst <= SEAT_TOLERANCE:
        return
    model = fm.model
    scene = model.scene
    seat = model.sprocket.pitch_radius(model.pitch)
    head = model.guide.params.head_radius
    if abs(head - seat) > SEAT_TOLERANCE:
        raise SceneError(
            f"{scene.source}: at t = 0 a roller is {1e3 * worst:.3g} mm inside a tooth: rollers on a head of "
            f"radius {head:.6g} m ('guide.head_radius') do not seat between teeth cut "
            f"for {model.sprocket_pitch:.6g} m ('sprocket.pitch'); give head_radius = \"sprocket\" (where this "
            "chain seats on these teeth)"
        )
    sp = scene.sprocket
    raise SceneError(
        f"{scene.source}: the rollers ({1000 * scene.chain.roller_radius:.4g} mm radius) sit "
        f"{1000 * worst:.3g} mm inside the sprocket's teeth at the start (teeth {1000 * sp.base_width:.4g} mm "
        f"wide, {1000 * sp.tooth_height:.4g} mm high, pitch {1000 * model.sprocket_pitch:.5g} mm): change "
        "chain.roller_radius or the teeth (sprocket.base_width, sprocket.tip_width, sprocket.tooth_height) "
        "to fit the pitch"
    )


def forward_dynamics(
    model,
    *,
    duration=None,
    progress=True,
    method=None,
    rtol=None,
    atol=None,
    outputs=None,
    effects=None,
    t_out=None,
    events=None,
):
    """Run the forward dynamics of ``model.scene``; see :func:`vibkit.simulate`.

    Keyword arguments override the scene's solver settings, outputs and effects (for benchmarks).
    """
    scene = model.scene
    run = scene.run
    solver = scene.solver
    effects = effect_options(scene.effects if effects is None else effects)
    outputs = scene.outputs["variables"] if outputs is None else outputs
    duration = duration or run.duration
    dt = run.output_step
    if t_out is None:
        t_out = output_times(duration, dt)
    fm = ForwardModel(model, effects, start=run.start)
    torque, ki = 0.0, 0.0
    if "motor" in effects:  # the motor's torque at t = 0 along the motion, in the sprocket's sense
        motor = effects["motor"]
        torque = motor.initial_torque * math.copysign(1.0, model.sprocket_speed(motor.speed)) if motor.speed else 0.0
        ki = motor.ki
    y0, d0 = initial_state(model, start=run.start, speed=run.initial_speed)
    check_seated(fm, y0, d0)  # the meshed start: the rollers seat between the teeth
    if torque != 0.0:  # then the teeth pressed into the rollers so as to carry the drive's torque
        y0, d0 = initial_state(
            model, start=run.start, speed=run.initial_speed, torque=torque, ki=ki, contact=effects.get("contact")
        )
    reset_closure(fm.info, d0)
    method = method or solver.method
    rtol = rtol or solver.rtol or default_rtol(effects)
    atol = atol or solver.atol_for(rtol)
    # dopri5 ends its steps where a roller crosses a curvature jump of the guide
    if events is None:
        events = solver.events
    t_events = None
    crossings, t_events = _events(model, fm)
    events, t_events = (crossings, t_events) if events else (None, None)
    table, closure = forward_table(model, fm, crossings[0], rtol, solver.closure, (y0[0], d0))
    y_out, stats = integrate(
        fm.prm,
        fm.work.arrays,
        y0,
        t_out,
        method=method,
        rtol=rtol,
        atol=atol,
        max_step=solver.max_step,
        first_step=solver.first_step,
        max_wall_time=math.inf if solver.max_wall_time is None else solver.max_wall_time,
        progress=progress,
        events=events,
        t_events=t_events,
        event_gap=event_gap(rtol),
        table=table,
    )
    stats["closure"] = closure
    reset_closure(fm.info, d0)  # the closure's first guess at the outputs: the initial delta, whatever the run's length
    # the outputs are taken on the side the motion goes at a breakpoint, whether or not the steps end there
    y_obs = _observed_states(y_out, crossings)
    return _post_process(fm, t_out, y_out, outputs, stats, y_obs, table)


def forward_table(model, fm, crossings, rtol, closure="table", start=(0.0, 0.0)):
    """The pitch table for the run and how the closure is taken: ("table", "exact" or "runs", and
    where the table cannot stand for the closure, why). ``start``: roller 1's coordinate and delta
    at the start (where the run-by-run closure measures its link error)."""
    if closure == "exact":
        return None, "exact"
    why = table_applies(model)
    if closure == "runs" or why is not None:
        runs = build_runs(model, fm.prm, empty_table(), *start)
        return runs, "runs" if why is None else f"runs ({why})"
    table, _, _ = checked_table(model, fm.prm, crossings, table_spacing(rtol))
    return table, "table"


ON_BREAKPOINT = 1e-11  # [m] as the integrator: a stage this close to a breakpoint is on its side


def _observed_states(y, events):
    """The states at which the outputs are evaluated: ``y``, with s0_1 moved ``ON_BREAKPOINT`` to the
    side the motion goes where it sits on a breakpoint of the guide.

    On a breakpoint (the start s0 = 0 is one) the right-hand side jumps, and its value there depended
    on where the closure's Newton iteration came from; the integrator takes it on the side the motion
    goes, and so do the outputs. The direction is that of s0dot_1, or where it is zero (a start from
    rest) that of the next output's s0_1.
    """
    if events is None or y.shape[0] == 0:
        return y
    cross, p0 = events
    cross = np.asarray(cross, dtype=float)
    if cross.size == 0:
        return y
    s = y[:, 0]
    r = s - np.floor(s / p0) * p0
    ext = np.concatenate([cross - p0, cross, cross + p0])
    k = np.clip(np.searchsorted(ext, r), 1, ext.size - 1)
    near = np.minimum(np.abs(ext[k] - r), np.abs(ext[k - 1] - r))
    hit = np.flatnonzero(near <= ON_BREAKPOINT)
    if hit.size == 0:
        return y
    y = y.copy()
    for j in hit:
        v = y[j, 1]
        if v == 0.0:
            nxt = y[j + 1, 0] - y[j, 0] if j + 1 < y.shape[0] else 0.0
            prv = y[j, 0] - y[j - 1, 0] if j > 0 else 0.0
            v = nxt if nxt != 0.0 else prv
        direction = 1.0 if v >= 0.0 else -1.0
        i = k[j] if abs(ext[k[j]] - r[j]) <= abs(ext[k[j] - 1] - r[j]) else k[j] - 1
        y[j, 0] = s[j] + (ext[i] - r[j]) + direction * ON_BREAKPOINT
    return y


def _events(model, fm):
    """Where the right-hand side is not smooth: values of s0_1 (one loop) and times.

    A roller on a curvature jump of the guide (or an end of a telescopic ramp); the middle roller of
    a passenger's step at the boarding or alighting place; a passenger's boarding or alighting time.
    """
    mode = fm.prm[PRM_IP][IP_PASSENGERS]
    rollers_at = []
    times = np.zeros(0)
    if mode:
        steps, pb, pa = fm.prm[PRM_PASS_STEP], fm.prm[PRM_PASS_BOARD], fm.prm[PRM_PASS_ALIGHT]
        if mode == PASSENGERS_BY_PLACE:
            rollers_at = [(int(model.step_rollers(int(st))[1]), v) for st, b, a in zip(steps, pb, pa) for v in (b, a)]
        else:
            times = np.unique(np.concatenate([pb, pa]))
    cross = model.chain.crossing_table(rollers_at=rollers_at)
    return (cross, model.guide.p0), times


# The tolerance at the reference contact stiffness (benchmarks/results/work_precision.md):
# with steps that end on the guide's breakpoints, rtol 1e-6 is the loosest that gives the converged
# contact history of the three shipped scenes, and the no-load chain with contact ten times softer
# needs 1e-7 (its last grazing contact moves from 33.33 s to 33.07 s at 1e-6): 1e-7 leaves a margin.
DEFAULT_RTOL = 1e-7
REFERENCE_STIFFNESS = 1e6  # [N/m^1.5] the study's contact stiffness
REFERENCE_DAMPING = 0.3  # [s/m] the largest contact damping right at DEFAULT_RTOL (las-palmas)


def default_rtol(effects):
    """The tolerance a forward scene gets when it sets no ``[solver] rtol``.

    rtol = 1e-7 min(1, (1e6 / k)^3, (0.3 / c)^2) for a contact stiffness k [N/m^exponent] and a
    contact damping c [s/m], at least 1e-11. Measured on the shipped scenes and their stiffness x0.1
    and x10 variants against runs at 1e-12
    (docs/explanation/numerics.md): at k = 1e7 the no-load chain needs
    1e-10 (las-palmas, damped, 1e-9), at k <= 1e6 every scene is right at 1e-7. A stiffer contact
    makes each impact a shorter, harder event, and the undamped chain carries the error of every
    impact in where it sits in its backlash. Damping: las-palmas (c = 0.3 s/m) is right at 1e-7,
    with c = 3 s/m it needs 1e-9 (the damping force 1.5 c k psi^e psidot changes within each impact
    as fast as the impact velocity does). Where no tolerance gives a converged history (an undamped
    stiff chain rattling chaotically) no default can be right: ``check`` reports such a run as sensitive.
    """
    effects = effect_options(effects)
    k = effects["contact"].stiffness if "contact" in effects else 0.0
    c = effects["contact"].damping if "contact" in effects else 0.0
    factor = 1.0
    if k > REFERENCE_STIFFNESS:
        factor = (REFERENCE_STIFFNESS / k) ** 3
    if c > REFERENCE_DAMPING:
        factor = min(factor, (REFERENCE_DAMPING / c) ** 2)
    if factor >= 1.0:
        return DEFAULT_RTOL
    return max(1e-11, float(f"{DEFAULT_RTOL * factor:.3g}"))


def event_gap(rtol):
    """How far from a breakpoint a step may end and count as ending on it: rtol metres, within
    [1e-11, 1e-6] m. [m]

    Ending a step a distance d short of (or past) a breakpoint errs by the jump of the right-hand
    side over d / v: measured on the conservative 44 s scene, d = 1 um costs about 1e-3 J, which is
    below the tolerance's own error at rtol 1e-6 and halves the steps taken again after an
    overshoot compared with 1e-9 m; tighter tolerances get a proportionally smaller gap, so that
    they converge (at a fixed 1 um the energy error stalls at 1e-3 J from rtol 1e-7 on).
    """
    return min(1e-6, max(1e-11, rtol))


NSCAL = 12  # delta, deltadot, motor, residual, speed, KE, PE, contact E, spring E, accel, drive/back flank


@kernel()
def _teeth_row(ind, cf, j, ind_t, frc_t):
    for q in range(ind_t.size):
        ind[j, q] = ind_t[q]
        cf[j, q] = frc_t[q]


@nb.njit(cache=True, error_model="numpy", nogil=True)
def _observe(
    t,
    y,
    prm,
    ws,
    inertia,
    light,
    need_tension,
    need_teeth,
    need_accel,
    mid,
    ridx,
    scal,
    tension,
    ind,
    cf,
    rk,
    light_contact,
    tb,
    light_table,
):
    """Every output quantity at the output states, in one compiled loop (see _post_process).

    Returns (status, index): status 0 ok, 1 closure failure, 2 non-finite state at ``index``.
    """
    fp = prm[PRM_FP]
    ip = prm[PRM_IP]
    mass = prm[PRM_MASS]
    pitches = prm[PRM_PITCHES]
    g = fp[FP_G] if ip[IP_GRAVITY] == 1 else 0.0
    k_s, pre, m_c = fp[FP_TENSIONER_STIFFNESS], fp[FP_PRELOAD], fp[FP_CARRIAGE_MASS]
    (s0a, kk, lam, xs, zs, part, alpha, beta, jac, gam, hacc, eta, sd, fx, fz, cand, ind_t, frc_t, info) = ws
    n = mass.size
    dy = np.empty(5)
    lam_buf = np.empty(n)
    lam_scratch = np.empty(n)
    rs_res = np.empty(n)
    d1 = d2 = d3 = info[INFO_DELTA]
    slope = 0.0
    for j in range(t.size):
        for i in range(5):
            if not math.isfinite(y[j, i]):
                return 2, j
        if light_table:
            # from the pitch table, as the integrator saw them (no closure residual asked); a chain
            # closed run by run from one walk where that closes it to first order
            if tb[TB_HEAD][HEAD_RUNS] != 0.0:
                if runs_observe(t[j], y[j], dy, prm, ws, need_teeth, tb) != 0:
                    return 1, j
            else:
                rhs(t[j], y[j], dy, prm, ws, need_teeth, tb)
            scal[j, 0] = info[INFO_DELTA]
            scal[j, 2] = info[INFO_MOTOR]
            scal[j, 10] = info[INFO_F_DRIVE]
            scal[j, 11] = info[INFO_F_BACK]
            if need_teeth:
                _teeth_row(ind, cf, j, ind_t, frc_t)
            continue
        if light:
            # positions only (delta, closure residual; torque from the state): no forces needed
            # delta extrapolated from the last three outputs, closed by chord steps on the last
            # Newton slope; a full Newton solve where they do not close
            guess = 3.0 * (d1 - d2) + d3 if j >= 3 else info[INFO_DELTA]
            d, walks, st = close_with_slope(
                prm[PRM_TABLE],
                fp[FP_P0],
                fp[FP_LT],
                y[j, 0],
                guess,
                slope,
                pitches,
                n,
                s0a,
                kk,
                lam,
                xs,
                zs,
                part,
                alpha,
                beta,
                fp[FP_CLOSURE_TOL],
            )
            if st != 0:
                return 1, j
            if walks > 2 and beta[n] > 0.0:
                slope = beta[n]
            d3 = d2
            d2 = d1
            d1 = d
            info[INFO_DELTA] = d
            scal[j, 0] = d
            scal[j, 3] = closure_residual(xs, zs, n, pitches)
            if ip[IP_MOTOR] == 1:
                scal[j, 2] = motor_torque(
                    fp[FP_SPEED_REF] - y[j, 3], y[j, 4], fp[FP_KP], fp[FP_KI], fp[FP_TORQUE_LIMIT]
                )[0]
            else:
                scal[j, 2] = 0.0
            scal[j, 10] = 0.0
            scal[j, 11] = 0.0
            if light_contact:
                # undamped contact forces need the positions only (the caller checked the damping)
                for i in range(n):
                    fx[i] = 0.0
                    fz[i] = 0.0
                ncand = contact_candidates(xs, zs, n, fp[FP_CX], fp[FP_CZ], fp[FP_REACH] + 1e-9, cand)
                for jj in range(ncand):
                    eta[cand[jj]] = 0.0
                    sd[cand[jj]] = 0.0
                clear_teeth(ind_t, frc_t)
                res = sprocket_contact(prm, y[j], xs, zs, eta, sd, cand, ncand, 0.0, fx, fz, ind_t, frc_t, need_teeth)
                scal[j, 10] = res[4]
                scal[j, 11] = res[5]
                if need_teeth:
                    _teeth_row(ind, cf, j, ind_t, frc_t)
            continue
        if tb[TB_SB].size > 0:
            # the closure from the table's delta (exact to 1e-13 m): one or two walks
            info[INFO_DELTA] = table_delta(tb, y[j, 0])
            info[INFO_AT] = y[j, 0]
            info[INFO_SLOPE] = 0.0
            info[INFO_CURVATURE] = 0.0
        if evaluate(t[j], y[j], dy, prm, ws, need_teeth) != 0:
            return 1, j
        sdot, sddot = y[j, 1], dy[1]
        d = info[INFO_DELTA]
        scal[j, 0] = d
        scal[j, 1] = info[INFO_DELTA_DOT]
        scal[j, 2] = info[INFO_MOTOR]
        scal[j, 3] = closure_residual(xs, zs, n, pitches)
        scal[j, 4] = math.hypot(jac[0, 0], jac[0, 1]) * abs(sdot)
        ke = 0.0
        pe = 0.0
        for i in range(n):
            ke += mass[i] * (jac[i, 0] ** 2 + jac[i, 1] ** 2)
            pe += mass[i] * zs[i]
        scal[j, 5] = 0.5 * ke * sdot * sdot + 0.5 * m_c * info[INFO_DELTA_DOT] ** 2 + 0.5 * inertia * y[j, 3] ** 2
        scal[j, 6] = g * pe
        scal[j, 7] = info[INFO_ENERGY_C]
        scal[j, 8] = pre * d + 0.5 * k_s * d * d
        scal[j, 10] = info[INFO_F_DRIVE]
        scal[j, 11] = info[INFO_F_BACK]
        if need_teeth:
            _teeth_row(ind, cf, j, ind_t, frc_t)
        if need_accel:
            ax = jac[mid, 0] * sddot + hacc[mid, 0]
            az = jac[mid, 1] * sddot + hacc[mid, 1]
            tx, tz = part[mid, PART_XS], part[mid, PART_ZS]
            scal[j, 9] = (ax * tx + az * tz) / math.hypot(tx, tz)
        else:
            scal[j, 9] = 0.0
        for q in range(ridx.size):
            i = ridx[q]
            rk[j, q, 0] = xs[i]
            rk[j, q, 1] = zs[i]
            rk[j, q, 2] = jac[i, 0] * sdot
            rk[j, q, 3] = jac[i, 1] * sdot
            rk[j, q, 4] = jac[i, 0] * sddot + hacc[i, 0]
            rk[j, q, 5] = jac[i, 1] * sddot + hacc[i, 1]
            rk[j, q, 6] = s0a[i]
        if need_tension:
            rd = m_c * info[INFO_DELTA_DDOT] + (pre + k_s * d)
            for i in range(n):
                resx = mass[i] * (jac[i, 0] * sddot + hacc[i, 0]) - fx[i]
                resz = mass[i] * (jac[i, 1] * sddot + hacc[i, 1]) - fz[i]
                rs_res[i] = part[i, PART_XS] * resx + part[i, PART_ZS] * resz
                rd += part[i, PART_XD] * resx + part[i, PART_ZD] * resz
            link_multipliers(part, xs, zs, n, rs_res, rd, 0.0, 0.0, 0.0, lam_buf, False, lam_scratch)
            for i in range(n):
                tension[j, i] = 2.0 * lam_buf[i] * pitches[i]
    return 0, 0


def _post_process(fm, t, y, outputs, stats, y_obs=None, table=None):
    """Outputs asked for, evaluated at the output states (only those asked for are computed);
    ``y_obs``: the states at which to evaluate them (:func:`_observed_states`), default ``y``."""
    y_obs = y if y_obs is None else y_obs
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
    mid = int(model.step_rollers(step)[1]) if need_accel else 0
    nteeth = model.sprocket.teeth
    scal = np.empty((nt, NSCAL))
    tension = np.empty((nt, n) if need_tension else (0, n))
    ind = np.empty((nt, nteeth) if need_teeth else (0, nteeth))
    cf = np.empty((nt, nteeth) if need_teeth else (0, nteeth))
    ridx = rollers.astype(np.int64) if need_roller else np.zeros(0, dtype=np.int64)
    rk = np.empty((nt, ridx.size, 7))
    # outputs that need only positions and the state skip the forces altogether
    light = want <= {
        "delta",
        "closure_residual",
        "sprocket_angle",
        "sprocket_speed",
        "motor_torque",
        "s0",
        "tensioner_displacement",
        "indentation",
        "contact_force",
        "flank_force",
    }
    light_contact = bool({"indentation", "contact_force", "flank_force"} & want) and "contact" in fm.effects
    if light_contact and fm.effects["contact"].damping != 0.0:
        light = False  # damped contact forces need the rollers' velocities
    scal[:] = np.nan
    # light outputs come from the table where the run used one, unless the closure residual is asked
    tb = table if table is not None else empty_table()
    light_table = table is not None and light and "closure_residual" not in want
    status, bad = _observe(
        t,
        y_obs,
        fm.prm,
        ws,
        model.sprocket.inertia,
        light,
        need_tension,
        need_teeth,
        need_accel,
        mid,
        ridx,
        scal,
        tension,
        ind,
        cf,
        rk,
        light_contact,
        tb,
        light_table,
    )
    if status != 0:
        what = "non-finite state in the output" if status == 2 else "the chain could not be closed"
        raise IntegrationError(what, float(t[bad]), y[bad])
    delta, ddot, motor, resid, speed, ke, pe, ce, se, acc_step = (scal[:, i] for i in range(10))
    flank = scal[:, 10:12]
    rp, rv, ra = rk[:, :, 0:2], rk[:, :, 2:4], rk[:, :, 4:6]
    if need_roller:
        add_flats(model, t, rk[:, :, 6], delta, ridx, rp, rv, ra)
    data = {}
    simple = {
        "delta": delta,
        "delta_dot": ddot,
        "sprocket_angle": y[:, 2],
        "sprocket_speed": y[:, 3],
        "motor_torque": motor,
        "chain_speed": speed,
        "closure_residual": resid,
        "s0": y[:, 0],
    }
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
    nominal = nominal_speed(fm.effects, scene.run)
    # a run from rest, or one whose drive takes up a running resistance at its start (a start-up either way), counts
    # its speed over its second half, after the start-up; one whose drive starts carrying it (the motor's
    # initial_torque: steady running from t = 0) has none
    carried = "motor" in fm.effects and fm.effects["motor"].initial_torque != 0.0
    start_up = abs(y[0, 1]) < 1e-9 or ("rolling_resistance" in fm.effects and not carried)
    speed, f_lp, counted_from = counted_speed(model, t, y[:, 0], nominal, from_rest=start_up)
    attrs = {
        "chain_speed_m_s": speed,
        # a run from rest counts its speed after the start-up: what reads a link pass from it reads it there too
        "speed_counted_from_s": counted_from,
        "speed_set_point_m_s": float(nominal),
        "link_pass_frequency_hz": f_lp,
        # from the table: the tabulated chain's own link-length error (the outputs were read from it)
        "closure_residual_max": float(tb[TB_HEAD][HEAD_LINK_ERROR]) if light_table else float(resid.max()),
        "closure_residual_max_units": "m",
        "solver_method": stats["method"],
        "solver_steps": stats["steps"],
        "solver_rejected": stats["rejected"],
        "solver_evaluations": stats["evaluations"],
        "solver_closure": stats.get("closure", "exact"),
        "solver_wall_time_s": float(stats["wall_time_s"]),
        "effects": ", ".join(sorted(fm.effects)),
    }
    if step is not None:
        attrs["step_accelerometer"] = int(step)
    attrs["links_per_step"] = int(scene.chain.links_per_step)
    return make_dataset(coords, data, attrs, scene)
