"""Force elements a scene can switch on, and the compiled right-hand side of the forward dynamics.

Only the effects a scene lists are evaluated: each is guarded by a flag, so a scene without contact
never visits the sprocket's teeth, one without passengers never looks at the clock, and so on. The
forces on the rollers are written once, in :func:`roller_forces`.

Effects (``[effects.*]`` in a scene):

gravity
    m g on every roller, along -z.
contact
    roller-tooth penalty contact on both flanks, f = k psi^e (1 + 1.5 c psidot) (:mod:`vibkit.model.sprocket`).
motor
    speed controller on the sprocket, M = kp (thetadot_ref - thetadot) + ki * integral, limited to
    +-torque_limit with conditional integration (no wind-up); thetadot_ref = -speed / R^P.
passengers
    m g shared by the three rollers of a step while it is aboard: by place (the default), while
    the step's middle roller is between the boarding and alighting places (found during the run,
    the integrator ends a step where it passes them); or between two given times.
tensioner
    carriage spring (preload + stiffness delta, opposing delta) and carriage mass.
rolling_resistance
    mu m g on every roller, opposing its velocity (regularised below 1 mm/s so the force is smooth).
"""

from __future__ import annotations

import math

import numpy as np

from ..runtime.kernel import kernel
from .chain import acceleration_terms, close_with_slope, fill_partials, sensitivity, velocity_coefficients
from .dynamics import reduced_equation
from .schema import EFFECT_OPTIONS, effect_options, gravity_of
from .slots import (
    FP,
    FP_CARRIAGE_MASS,
    FP_CLOSURE_TOL,
    FP_CX,
    FP_CZ,
    FP_DAMPING,
    FP_EXPONENT,
    FP_G,
    FP_INERTIA,
    FP_KI,
    FP_KP,
    FP_LT,
    FP_P0,
    FP_PRELOAD,
    FP_REACH,
    FP_ROLLING,
    FP_SPEED_REF,
    FP_STIFFNESS,
    FP_TENSIONER_STIFFNESS,
    FP_TORQUE_LIMIT,
    INFO_ACTIVE,
    INFO_AT,
    INFO_CURVATURE,
    INFO_DELTA,
    INFO_DELTA_DDOT,
    INFO_DELTA_DOT,
    INFO_DH_DDELTA,
    INFO_ENERGY_C,
    INFO_F_BACK,
    INFO_F_DRIVE,
    INFO_MEMORY,
    INFO_MEMORY_END,
    INFO_MOTOR,
    INFO_NAMES,
    INFO_SLOPE,
    INFO_TORQUE_C,
    INFO_WALKS,
    INFO_WORST,
    IP,
    IP_CONTACT,
    IP_GRAVITY,
    IP_LINKS_PER_STEP,
    IP_MOTOR,
    IP_N,
    IP_PASSENGERS,
    IP_ROLLING,
    IP_TENSIONER,
    PASSENGERS_BY_TIME,
    PRM_FP,
    PRM_RADII,
    PRM_TEETH,
    WS_NAMES,
)
from .sprocket import contact_kernel

__all__ = [
    "pack_parameters",
    "evaluate",
    "motor_torque",
    "passenger_loads",
    "contact_candidates",
    "roller_forces",
    "left_out",
    "carries_all",
    "FP",
    "IP",
]


class Work:
    """Scratch arrays of one model (allocated once, reused by every evaluation)."""

    def __init__(self, n, nteeth):
        self.arrays = (
            np.empty(n + 1),
            np.empty(n + 1, dtype=np.int64),
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty((n + 1, 12)),
            np.empty(n + 1),
            np.empty(n + 1),
            np.empty((n, 2)),
            np.empty(n),
            np.empty((n, 2)),
            np.empty(n),
            np.empty(n),
            np.empty(n),
            np.empty(n),
            np.empty(n, dtype=np.int64),
            np.zeros(nteeth),
            np.zeros(nteeth),
            np.zeros(len(INFO_NAMES)),
        )
        if len(self.arrays) != len(WS_NAMES):
            raise RuntimeError("Work.arrays and vibkit.model.slots.WS_NAMES disagree")


def pack_parameters(model, effects: dict, *, start: float = 0.0):
    """Parameter arrays for the compiled kernels from a model and the scene's effects (typed options or
    plain tables: :func:`vibkit.model.schema.effect_options`)."""
    effects = effect_options(effects)
    n = model.n
    fp = np.zeros(len(FP))
    ip = np.zeros(len(IP), dtype=np.int64)
    geo = model.geometry
    fp[FP["p0"]] = model.guide.p0
    fp[FP["lt"]] = model.guide.params.tensioner_length
    fp[FP["pitch"]] = model.pitch
    fp[FP["inertia"]] = model.sprocket.inertia
    fp[FP["r_d"]] = float(model.radii.max())  # the largest roller: how far a roller can reach
    fp[FP["cx"]], fp[FP["cz"]] = model.centre
    fp[FP["root_r"]] = geo["root_radius"]
    fp[FP["psi"]] = geo["tooth_pitch"]
    fp[FP["tol"]] = model.chain.tol
    # contact candidates: roller centres within reach of a tooth's farthest corner (the tip corners
    # B and C lie beyond R^F + h: sqrt((R^F + h)^2 + (tip width / 2)^2))
    loc = model.corners_local
    fp[FP["reach"]] = float(np.max(np.hypot(loc[:, 0], geo["root_radius"] + loc[:, 1]))) + fp[FP["r_d"]]
    ip[IP["n"]] = n
    ip[IP["nteeth"]] = model.sprocket.teeth
    ip[IP["links_per_step"]] = model.scene.chain.links_per_step
    for name in effects:  # every effect's switch (IP_NAMES names them as the schema does)
        ip[IP[name]] = 1
    if "gravity" in effects:
        fp[FP["g"]] = effects["gravity"].g
    if "contact" in effects:
        o = effects["contact"]
        fp[FP["k"]], fp[FP["expo"]], fp[FP["damp"]] = o.stiffness, o.exponent, o.damping
    if "motor" in effects:
        o = effects["motor"]
        fp[FP["kp"]], fp[FP["ki"]] = o.kp, o.ki
        fp[FP["wref"]] = model.sprocket_speed(o.speed)  # motor.speed is the chain speed on the straight
        fp[FP["tlim"]] = o.torque_limit
    pm = np.zeros(0)
    ps = np.zeros(0, dtype=np.int64)
    pb = np.zeros(0)
    pa = np.zeros(0)
    if "passengers" in effects:
        o = effects["passengers"]
        by_place, pb, pa = model.passenger_schedule(o, start)
        ip[IP["passengers"]] = 2 if by_place else 1
        pm = np.asarray(o.mass, dtype=float)
        ps = np.asarray(o.step, dtype=np.int64)
        if "gravity" not in effects:
            fp[FP["g"]] = gravity_of(effects)
    if "tensioner" in effects:
        o = effects["tensioner"]
        fp[FP["k_s"]], fp[FP["preload"]], fp[FP["m_c"]] = o.stiffness, o.preload, o.mass
    if "rolling_resistance" in effects:
        fp[FP["mu_rr"]] = effects["rolling_resistance"].coefficient
        if "gravity" not in effects:
            fp[FP["g"]] = gravity_of(effects)
    prm = (model.guide.table, model.corners_local, fp, ip, model.mass.copy(), pm, ps, pb, pa, model.chain.pitches)
    return prm + (model.radii.copy(), model.teeth)


def reset_closure(info, delta):
    """Start the next evaluation's closure from ``delta`` alone (no prediction, no stored slope)."""
    info[INFO_DELTA] = delta
    info[INFO_MEMORY:INFO_MEMORY_END] = 0.0
    info[INFO_CURVATURE] = 0.0


@kernel()
def motor_torque(err, integral, kp, ki, limit):
    """Speed controller: M = kp err + ki integral, limited to +-limit [N m], and the rate of the
    error integral, held at zero while the limit is pushed further (no wind-up).

    ``err`` = thetadot_ref - thetadot [rad/s]; ``integral`` its time integral [rad].
    """
    motor = kp * err + ki * integral
    derr = err
    if motor > limit:
        motor = limit
        if err > 0.0:
            derr = 0.0
    elif motor < -limit:
        motor = -limit
        if err < 0.0:
            derr = 0.0
    return motor, derr


@kernel()
def rolling_force(vx, vz, f):
    """Rolling resistance of magnitude ``f`` [N] against a roller's velocity (vx, vz) [m/s],
    regularised below 1 mm/s so that it is smooth."""
    sp = math.sqrt(vx * vx + vz * vz + 1e-6)
    return -f * vx / sp, -f * vz / sp


@kernel()
def clear_teeth(ind_t, frc_t):
    """Zero the per-tooth indentation and force of the next contact evaluation."""
    for j in range(ind_t.size):
        ind_t[j] = 0.0
        frc_t[j] = 0.0


@kernel(inline="always")
def sprocket_contact(prm, y, xs, zs, vx, vz, cand, ncand, damping, fx, fz, ind_t, frc_t, want_teeth):
    """:func:`vibkit.model.sprocket.contact_kernel` on the ``ncand`` candidates ``cand`` (places xs, zs,
    velocities vx, vz) with the scene's sprocket (``prm``) at the state ``y`` (its angle and speed) and the
    contact's ``damping``: adds the forces to fx, fz and returns what contact_kernel returns."""
    fp = prm[PRM_FP]
    return contact_kernel(
        xs,
        zs,
        vx,
        vz,
        cand,
        ncand,
        y[2],
        y[3],
        fp[FP_CX],
        fp[FP_CZ],
        prm[PRM_TEETH],
        prm[PRM_RADII],
        fp[FP_STIFFNESS],
        fp[FP_EXPONENT],
        damping,
        fx,
        fz,
        ind_t,
        frc_t,
        want_teeth,
    )


@kernel(inline="always")
def within_reach(x, z, cx, cz, reach2):
    """Whether a roller centre (x, z) is closer than sqrt(reach2) to the sprocket centre (cx, cz)."""
    dxc = x - cx
    dzc = z - cz
    return dxc * dxc + dzc * dzc < reach2


@kernel()
def contact_candidates(xs, zs, n, cx, cz, reach, cand):
    """The contact candidates among rollers 0 .. n-1: those whose centre is closer than ``reach`` [m]
    to the sprocket centre (cx, cz) (whose circle can reach a tooth). Their indices go to the front
    of ``cand``, in order; returns how many."""
    ncand = 0
    reach2 = reach * reach
    for i in range(n):
        if within_reach(xs[i], zs[i], cx, cz, reach2):
            cand[ncand] = i
            ncand += 1
    return ncand


@kernel(inline="always")
def step_roller(ps, jp, r, n, k):
    """Index of roller ``r`` (0 .. k - 1; the middle one, for 3 or 4 rollers, is 1) of passenger ``jp``'s
    step (``ps`` 1-based) on a chain of ``k`` rollers per step."""
    return (k * (ps[jp] - 1) + r) % n


@kernel(inline="always")
def aboard(jp, where, pb, pa):
    """Whether passenger ``jp`` is aboard at ``where`` (a time, or its step's middle-roller place)."""
    return pb[jp] <= where < pa[jp]


@kernel(inline="always")
def step_load(jp, pm, g, k):
    """Weight [N] passenger ``jp`` puts on each of the ``k`` rollers of its step: m g / k."""
    return pm[jp] * g / k


@kernel()
def passenger_loads(t, mode, s0, pm, ps, pb, pa, g, n, k, fz):
    """Subtract from ``fz`` [N] the weight of every passenger aboard, shared by its step's ``k`` rollers.

    ``mode`` 1: aboard by time (board <= t < alight); 2: by place, while the step's middle roller's
    unwrapped s0 (``s0``, the rollers' coordinates) is between the boarding and alighting places.
    """
    for jp in range(pm.size):
        where = t if mode == PASSENGERS_BY_TIME else s0[step_roller(ps, jp, 1, n, k)]
        if aboard(jp, where, pb, pa):
            w = step_load(jp, pm, g, k)
            for r in range(k):
                fz[step_roller(ps, jp, r, n, k)] -= w


@kernel()
def roller_forces(t, fp, ip, mass, pm, ps, pb, pa, s0, vel, scale, n, fx, fz):
    """The applied forces [N] on rollers 0 .. n-1 into ``fx``, ``fz`` (overwritten): every effect the
    scene switches on (``ip``) that acts on the rollers themselves: gravity (m g along -z), the
    passengers' weight (:func:`passenger_loads`; ``s0`` the rollers' unwrapped coordinates for those
    aboard by place) and rolling resistance against each roller's velocity ``vel[i] * scale``
    (:func:`rolling_force`; ``vel`` (n, 2), with ``scale`` 1, or J with ``scale`` = s0_1-dot).

    The one place such a force is written: the exact closure (:func:`evaluate_forces`, which the run-by-run
    closure hands its configuration to) and the study's formulation
    (:func:`vibkit.analyses.study_kernels.assemble`) call it. The closed-form right-hand sides (the pitch
    table, the runs' fast path) declare the effects they carry (``TABLE_CARRIES``, ``FAST_CARRIES``) and
    hand a scene with any other to it (:func:`left_out`, :func:`carries_all`).
    """
    g = fp[FP_G]
    for i in range(n):
        fx[i] = 0.0
        fz[i] = -mass[i] * g if ip[IP_GRAVITY] == 1 else 0.0
    if ip[IP_PASSENGERS] != 0:
        passenger_loads(t, ip[IP_PASSENGERS], s0, pm, ps, pb, pa, g, n, ip[IP_LINKS_PER_STEP], fz)
    if ip[IP_ROLLING] == 1:
        mu = fp[FP_ROLLING]
        for i in range(n):
            rx, rz = rolling_force(vel[i, 0] * scale, vel[i, 1] * scale, mu * mass[i] * g)
            fx[i] += rx
            fz[i] += rz


def left_out(carries) -> np.ndarray:
    """The switches (``ip`` slots) of the schema's effects that a closed-form right-hand side does not
    carry (``carries``: effect names): a scene with any of them on must take the general path. Derived
    from :data:`vibkit.model.schema.EFFECT_OPTIONS` at import, so an effect added to the schema is left
    out of every closed form until that form says it carries it."""
    unknown = set(carries) - set(EFFECT_OPTIONS)
    if unknown:
        raise RuntimeError(f"a right-hand side carries effects the schema does not declare: {sorted(unknown)}")
    return np.array([IP[name] for name in EFFECT_OPTIONS if name not in carries], dtype=np.int64)


@kernel(inline="always")
def carries_all(ip, left):
    """Whether the scene (``ip``) switches on none of the effects ``left`` (from :func:`left_out`)."""
    for j in left:
        if ip[j] != 0:
            return False
    return True


@kernel()
def finish(y, dy, info, fp, ip, sddot, torque_c, energy_c, worst, active, f_drive, f_back):
    """The state's rates from roller 1's acceleration ``sddot`` and the contact kernel's results
    (torque, energy, max indentation, active contacts, drive- and back-flank forces): fills ``dy``
    and the info slots of the motor torque and the contact's results."""
    motor = 0.0
    derr = 0.0
    if ip[IP_MOTOR] == 1:
        motor, derr = motor_torque(fp[FP_SPEED_REF] - y[3], y[4], fp[FP_KP], fp[FP_KI], fp[FP_TORQUE_LIMIT])
    dy[0] = y[1]
    dy[1] = sddot
    dy[2] = y[3]
    dy[3] = (motor + torque_c) / fp[FP_INERTIA]
    dy[4] = derr
    info[INFO_MOTOR] = motor
    info[INFO_TORQUE_C] = torque_c
    info[INFO_ENERGY_C] = energy_c
    info[INFO_WORST] = worst
    info[INFO_ACTIVE] = active
    info[INFO_F_DRIVE] = f_drive
    info[INFO_F_BACK] = f_back


@kernel()
def evaluate(t, y, dy, prm, ws, want_teeth):
    """Right-hand side of the forward dynamics; fills ``dy`` and returns a status code.

    State y = [s0_1, s0dot_1, theta, thetadot, integral of the speed error]. On return the work
    arrays ``ws`` hold the closed configuration, velocities and forces at (t, y), and ``ws[WS_INFO]``
    holds the ``INFO_*`` slots of :mod:`vibkit.model.slots` (delta and its rates, the motor and
    contact quantities, and the closure's memory); the next evaluation predicts delta from
    ``INFO_DELTA``, ``INFO_AT``, ``INFO_SLOPE`` and ``INFO_CURVATURE`` and closes the chain with the
    slope ``INFO_DH_DDELTA`` (zero them to close from delta alone: see ``reset_closure``). Status 0
    is success; 1 means the chain could not be closed (the state left the tensioner's travel).
    """
    tab, loc, fp, ip, mass, pm, ps, pb, pa, pitches, radii, _ = prm
    (s0, kk, lam, xs, zs, part, alpha, beta, jac, gam, hacc, eta, sd, fx, fz, cand, ind_t, frc_t, info) = ws
    n = ip[IP_N]
    p0, lt = fp[FP_P0], fp[FP_LT]
    sdot = y[1]
    # the closure from delta predicted along ddelta/ds0_1 of the last evaluation, with its exact
    # dh/ddelta (the closure's memory in info); the same tolerance as a full Newton solve
    ds = y[0] - info[INFO_AT]
    guess = info[INFO_DELTA] + ds * (info[INFO_SLOPE] + 0.5 * info[INFO_CURVATURE] * ds)
    delta, walks, st = close_with_slope(
        tab,
        p0,
        lt,
        y[0],
        guess,
        info[INFO_DH_DDELTA],
        pitches,
        n,
        s0,
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
        return 1
    info[INFO_WALKS] += walks
    # partials and sensitivities over the n rollers and the ghost: beta[n] is dh/ddelta here
    fill_partials(tab, p0, s0, kk, lam, delta, n + 1, part)
    sensitivity(part, xs, zs, n + 1, alpha, beta)
    c = velocity_coefficients(part, xs, zs, n, alpha, beta, jac, gam)
    e = acceleration_terms(part, xs, zs, n, alpha, beta, gam, c, sdot, hacc, eta, sd)
    return evaluate_forces(t, y, dy, prm, ws, want_teeth, delta, c, e, beta[n])


@kernel()
def evaluate_forces(t, y, dy, prm, ws, want_teeth, delta, c, e, dh):
    """The forces and the reduced equation of :func:`evaluate` from a closed configuration: ``ws``
    holding every roller's s0, position, J and h, with delta, c = d delta/ds0_1, e (delta-ddot =
    c s-ddot + e) and ``dh`` = dh/d delta of the closure (its memory for the next evaluation).
    Returns 0."""
    tab, loc, fp, ip, mass, pm, ps, pb, pa, pitches, radii, _ = prm
    (s0, kk, lam, xs, zs, part, alpha, beta, jac, gam, hacc, eta, sd, fx, fz, cand, ind_t, frc_t, info) = ws
    n = ip[IP_N]
    sdot = y[1]
    roller_forces(t, fp, ip, mass, pm, ps, pb, pa, s0, jac, sdot, n, fx, fz)
    torque_c, energy_c, worst, active, f_drive, f_back = 0.0, 0.0, 0.0, 0, 0.0, 0.0
    if want_teeth:
        clear_teeth(ind_t, frc_t)
    if ip[IP_CONTACT] == 1:
        ncand = contact_candidates(xs, zs, n, fp[FP_CX], fp[FP_CZ], fp[FP_REACH] + 1e-9, cand)
        # roller velocities of the candidates (for damping): v = J sdot, stored in eta/sd scratch
        for jj in range(ncand):
            i = cand[jj]
            eta[i] = jac[i, 0] * sdot
            sd[i] = jac[i, 1] * sdot
        torque_c, energy_c, worst, active, f_drive, f_back = sprocket_contact(
            prm, y, xs, zs, eta, sd, cand, ncand, fp[FP_DAMPING], fx, fz, ind_t, frc_t, want_teeth
        )
    f_c = 0.0
    m_c = 0.0
    if ip[IP_TENSIONER] == 1:
        f_c = -(fp[FP_PRELOAD] + fp[FP_TENSIONER_STIFFNESS] * delta)
        m_c = fp[FP_CARRIAGE_MASS]
    m_eff, q = reduced_equation(jac, hacc, fx, fz, mass, c, e, m_c, f_c)
    sddot = q / m_eff
    finish(y, dy, info, fp, ip, sddot, torque_c, energy_c, worst, active, f_drive, f_back)
    remember_closure(info, y, sddot, delta, c, e, dh)
    return 0


@kernel(inline="always")
def remember_closure(info, y, sddot, delta, c, e, dh):
    """The closure's results and memory in ``info`` after an evaluation at the state ``y``: delta and its
    rates (delta-dot = c s-dot, delta-ddot = c s-ddot + e), and what the next evaluation predicts delta
    from (here, the slope c, d2delta/ds0_1^2 = e / s-dot^2 for a second-order prediction, and ``dh`` =
    dh/ddelta of the closure)."""
    sdot = y[1]
    info[INFO_DELTA] = delta
    info[INFO_AT] = y[0]
    info[INFO_SLOPE] = c
    info[INFO_DH_DDELTA] = dh
    info[INFO_CURVATURE] = e / (sdot * sdot) if sdot * sdot > 1e-12 else 0.0
    info[INFO_DELTA_DOT] = c * sdot
    info[INFO_DELTA_DDOT] = c * sddot + e
