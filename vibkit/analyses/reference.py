"""The study's own formulation of the forward dynamics, kept as the independent reference.

The study (model.md section 3; its chapters 5-7) describes the chain with all p + 2 coordinates

    q = [s0_1 ... s0_p, delta, theta]

(each roller's arc length on the *undeformed* guide, the tensioner displacement and the sprocket
angle), the p closure constraints C_i = |r_{i+1} - r_i|^2 - L^2 (the last one joining roller p to
roller 1) enforced with Lagrange multipliers at the acceleration level, Baumgarte stabilisation
against drift, and Matlab's ode15s (a variable-order BDF/NDF method) with
RelTol = AbsTol = MaxStep = 1e-3. This module is a faithful port of that formulation: it is the
independent check of :mod:`vibkit.analyses.forward` (which integrates the 2-DOF system in the independent
coordinate s0_1, closing the chain link by link at every evaluation) and the baseline of the speed
comparison in ``benchmarks/bench_reference.py``.

Every evaluation of the right-hand side assembles and solves the sparse augmented (KKT) system

    [ M       Phi_q^T ] [ qddot  ]   [ Q + Q_v                                   ]
    [ Phi_q   0       ] [ lambda ] = [ gamma - 2 alpha Phi_q qdot - beta^2 Phi    ]

with M = sum_i m_i B_i^T B_i (+ m_c on delta, + I on theta), B_i = dr_i/dq (2 x n, non-zero only in
the columns of s0_i and delta), Q_v = -sum_i m_i B_i^T w_i the quadratic-velocity forces
(w_i = r_ss s0dot_i^2 + 2 r_sd s0dot_i deltadot + r_dd deltadot^2), Q the generalised applied
forces (gravity, roller-tooth contact, motor, and whatever else the scene switches on), and
gamma = -(Phi_q qdot)_q qdot. Phi_q is sparse: row i touches s0_i, s0_{i+1} and delta only. The
link tensions are T_i = 2 lambda_i L.

A property of the study's coordinates worth knowing when comparing: the map s0 -> r is continuous
but not continuously differentiable where a telescopic tensioner run (whose points are mapped
linearly, the study's eqs. 4-5 to 4-8) meets a fixed segment, so a roller crossing such a joint
with a continuous s0dot changes its physical speed by the factor (Lt - delta)/Lt; the constraint
then holds only through Baumgarte's correction for a short while (the link lengths err by about
0.2 mm at the default alpha = beta = 50 1/s). vibkit's guide uses a C1 map instead
(:func:`vibkit.model.guide.local_map`); ``coordinate_map="vibkit"`` runs the same equations in that
coordinate, which separates the study's equations (checked to integration accuracy) from its choice
of coordinate (a small, stated disagreement).
"""

from __future__ import annotations

import math
import time

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..model.effects import pack_parameters
from ..model.escalator import EscalatorModel
from ..model.guide import S0, SIGP, local_inverse
from ..model.scene import Scene, load_scene
from ..model.schema import effect_options, nominal_speed
from .forward import initial_state
from .integrate import IntegrationError
from .results import make_dataset
from .study_kernels import assemble, kkt_pattern, study_closure_residual, study_kinematics

__all__ = ["StudyFormulation", "run_study", "BAUMGARTE_ALPHA", "BAUMGARTE_BETA", "STUDY_SETTINGS"]

BAUMGARTE_ALPHA = 50.0
"""Default Baumgarte damping constant alpha. [1/s]

The study names alpha and beta but gives no values (its section 7.2.3 asks for values "not too
large, not too small"). alpha = beta makes the constraint error critically damped,
e'' + 2 alpha e' + beta^2 e = 0, with a time constant of 20 ms: short against the 0.27 s link-pass
period, long against the 1 ms step limit. On the first second of ``sim/thesis-forward.toml`` the
link-length error then stays below about 0.2 mm; it scales as 1/alpha (1 mm at alpha = 10, 0.06 mm
at 200), while the Baumgarte forces that correct it grow with alpha (their imprint on the link
tensions is about 6 N at alpha = 10, 18 N at 50 and 54 N at 200, against tensions of 3.5 kN).
"""

BAUMGARTE_BETA = 50.0
"""Default Baumgarte stiffness constant beta (natural frequency of the constraint error). [1/s]"""

STUDY_SETTINGS = {"rtol": 1e-3, "atol": 1e-3, "max_step": 1e-3}
"""The study's odeset (its table 13): RelTol, AbsTol [state units], MaxStep [s]."""

_SOLVE_IVP_METHODS = ("BDF", "Radau", "LSODA", "RK45", "RK23", "DOP853")


class StudyFormulation:
    """The study's equations of motion in all p + 2 coordinates (see module docstring).

    Parameters
    ----------
    model : EscalatorModel
        Guide, chain and sprocket of a scene.
    effects : dict
        Effect name -> options, as ``Scene.effects`` (gravity, contact, motor, passengers,
        tensioner, rolling_resistance).
    alpha, beta : float
        Baumgarte constants of C'' + 2 alpha C' + beta^2 C = 0. [1/s]
    coordinate_map : {"study", "vibkit"}
        How s0 maps onto the telescopic runs: "study" is the study's linear map (dr/ds0 jumps at
        the four ends of the runs, see module docstring); "vibkit" is the C1 map of
        :func:`vibkit.model.guide.local_map`, the coordinate of :mod:`vibkit.analyses.forward`. The equations are
        the same; only the coordinate differs.

    Attributes
    ----------
    p : int
        Number of rollers (= number of closure constraints).
    n : int
        Number of coordinates, p + 2.
    size : int
        Length of the state y = [q, qdot, integral of the sprocket speed error], 2 n + 1.
    evaluations : int
        Calls of :meth:`rhs` so far.

    Notes
    -----
    Indices in q: ``0 .. p-1`` the rollers' s0 (unwrapped, increasing) [m], ``p`` delta [m],
    ``p + 1`` theta [rad]. The KKT matrix of :meth:`kkt` is ordered [q, lambda]; :meth:`solve`
    factorises the same matrix with the unknowns interleaved (s0_1, lambda_1, s0_2, lambda_2, ...,
    delta, theta), an ordering in which the sparse LU makes almost no fill-in.
    """

    def __init__(
        self,
        model,
        effects: dict,
        *,
        alpha: float = BAUMGARTE_ALPHA,
        beta: float = BAUMGARTE_BETA,
        coordinate_map: str = "study",
    ):
        if coordinate_map not in ("study", "vibkit"):
            raise ValueError(f"coordinate_map must be 'study' or 'vibkit', got {coordinate_map!r}")
        for name, value in (("alpha", alpha), ("beta", beta)):
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"Baumgarte constant {name} must be a finite number >= 0 [1/s], got {value!r}")
        self.model = model
        self.effects = effects = effect_options(effects)
        self.alpha = float(alpha)
        self.beta = float(beta)
        self.coordinate_map = coordinate_map
        self.linear = coordinate_map == "study"
        if "passengers" in effects and isinstance(list(effects["passengers"].board)[0], str):
            raise ValueError(
                "the study's formulation takes passengers by time (effects.passengers.board and "
                "alight in seconds), not by place"
            )
        self.prm = pack_parameters(model, effects)
        # link j joins roller j and j + 1; its length (all equal unless the chain models worn links)
        pitches = getattr(model.chain, "pitches", None)
        self.pitches = np.ascontiguousarray(
            pitches if pitches is not None else np.full(model.n, model.pitch), dtype=float
        )
        if self.pitches.shape != (model.n,):
            raise ValueError(f"link pitches must have shape ({model.n},), got {self.pitches.shape}")
        self.p = model.n
        self.n = self.p + 2
        self.size = 2 * self.n + 1
        self.evaluations = 0
        p, n = self.p, self.n
        nteeth = model.sprocket.teeth
        self.work = (
            np.empty((p, 12)),
            np.empty((p, 2)),
            np.empty((p, 2)),
            np.empty(p),
            np.empty(p),
            np.empty(p, dtype=np.int64),
            np.zeros(nteeth),
            np.zeros(nteeth),
            np.empty(p),
            np.empty(p),
            np.empty(p),
            np.empty(p),
        )
        rows, cols = kkt_pattern(p)
        self._dim = n + p
        # position of each unknown in the interleaved ordering used for the factorisation
        pos = np.empty(self._dim, dtype=np.int64)
        pos[:p] = 2 * np.arange(p)
        pos[n:] = 2 * np.arange(p) + 1
        pos[p], pos[p + 1] = 2 * p, 2 * p + 1
        self._pos = pos
        self._natural = self._layout(rows, cols)
        self._interleaved = self._layout(pos[rows], pos[cols])
        self._data = np.empty(rows.size)
        self._rhs = np.empty(self._dim)

    def _layout(self, rows, cols):
        """CSC indices and pointers of the fixed pattern, and where each assembled value goes."""
        probe = sp.csc_matrix((np.arange(1, rows.size + 1, dtype=float), (rows, cols)), shape=(self._dim,) * 2)
        probe.sort_indices()
        if probe.nnz != rows.size:
            raise RuntimeError("the KKT pattern has duplicate entries")
        return probe.data.astype(np.int64) - 1, probe.indices.copy(), probe.indptr.copy()

    def _matrix(self, layout):
        order, indices, indptr = layout
        return sp.csc_matrix((self._data[order], indices, indptr), shape=(self._dim,) * 2)

    # -- the equations ----------------------------------------------------------------------------
    def _fill(self, t, y):
        y = np.ascontiguousarray(y, dtype=float)
        if y.shape != (self.size,):
            raise ValueError(f"state y must have shape ({self.size},), got {y.shape}")
        return assemble(
            float(t), y, self.prm, self.pitches, self.linear, self.alpha, self.beta, self.work, self._data, self._rhs
        )

    def kkt(self, t: float, y: np.ndarray):
        """The augmented system at (t, y), ordered [q, lambda].

        Returns
        -------
        matrix : scipy.sparse.csc_matrix (n + p, n + p)
            [[M, Phi_q^T], [Phi_q, 0]].
        rhs : ndarray (n + p,)
            [Q + Q_v; gamma - 2 alpha Phi_q qdot - beta^2 Phi].
        extras : tuple
            (motor torque [N m], contact torque on the sprocket [N m], rate of the speed-error
            integral [rad/s]).
        """
        extras = self._fill(t, y)
        return self._matrix(self._natural), self._rhs.copy(), extras

    def solve(self, t: float, y: np.ndarray):
        """Accelerations qddot (n,) [m/s^2, rad/s^2] and multipliers lambda (p,) [N/m] at (t, y),
        with the extras of :meth:`kkt`."""
        extras = self._fill(t, y)
        b = np.empty(self._dim)
        b[self._pos] = self._rhs
        # threshold pivoting that prefers the diagonal keeps the band: about 2.5k non-zeros in L + U
        x = splu(self._matrix(self._interleaved), permc_spec="NATURAL", diag_pivot_thresh=0.1).solve(b)
        sol = x[self._pos]
        return sol[: self.n], sol[self.n :], extras

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """d/dt [q, qdot, integral] (the function handed to the integrator)."""
        self.evaluations += 1
        n = self.n
        qdd, _, extras = self.solve(t, y)
        dy = np.empty(self.size)
        dy[:n] = y[n : 2 * n]
        dy[n : 2 * n] = qdd
        dy[2 * n] = extras[2]
        return dy

    # -- states -----------------------------------------------------------------------------------
    def state_from_independent(self, y_ind) -> np.ndarray:
        """The study's state of the chain described by vibkit's state y_ind = [s0_1, s0dot_1, theta,
        thetadot, integral] (:mod:`vibkit.analyses.forward`).

        The conversion goes through the physical configuration: the chain is closed link by link
        (:meth:`vibkit.model.chain.Chain.configure`), each roller's study coordinate follows from its
        segment and local arc length, and its rate from its velocity, s0dot_i = (v_i - r_d,i deltadot).r_s,i
        / |r_s,i|^2. So C = 0 and Phi_q qdot = 0 to rounding, whatever coordinate map vibkit's guide uses.
        """
        model = self.model
        tab, p0 = model.guide.table, model.guide.p0
        p, n = self.p, self.n
        conf = model.chain.configure(float(y_ind[0]))
        jac, _, c, _, _ = model.chain.jacobian(conf)
        y = np.zeros(self.size)
        wrapped = conf.s0 - p0 * np.floor(conf.s0 / p0)
        k = conf.segment
        loc_vibkit = wrapped - tab[k, S0]
        loc_vibkit[loc_vibkit < -1e-9] += p0
        if self.linear:
            loc_study = conf.lam / (1.0 + tab[k, SIGP] * conf.delta)
        else:
            loc_study = np.array([local_inverse(tab, kk, lam, conf.delta) for kk, lam in zip(k, conf.lam)])
        y[:p] = conf.s0 - loc_vibkit + loc_study
        y[p] = conf.delta
        y[p + 1] = y_ind[2]
        part = np.empty((p, 12))
        study_kinematics(tab, p0, y[:n], np.zeros(n), p, self.linear, part, np.empty((p, 2)), np.empty((p, 2)))
        v = jac * y_ind[1]
        ddot = c * y_ind[1]
        rs, rd = part[:, 2:4], part[:, 4:6]
        y[n : n + p] = np.sum((v - rd * ddot) * rs, axis=1) / np.sum(rs * rs, axis=1)
        y[n + p] = ddot
        y[n + p + 1] = y_ind[3]
        y[2 * n] = y_ind[4]
        return y

    def initial_state(self, *, start: float = 0.0, speed: float = 0.0) -> np.ndarray:
        """Closed, meshed state with roller 1 at ``start`` [m of undeformed guide] moving at ``speed`` [m/s].

        The same initial condition as :func:`vibkit.analyses.forward.initial_state` (the sprocket meshes the
        rollers on the head midway between teeth and turns with the chain), in the study's coordinates.
        """
        y_ind, _ = initial_state(self.model, start=float(start), speed=float(speed))
        return self.state_from_independent(y_ind)

    def observe(self, t: float, y: np.ndarray) -> dict:
        """Derived quantities at one state.

        Returns
        -------
        dict
            ``delta`` [m], ``chain_speed`` [m/s] (roller 1), ``sprocket_angle`` [rad],
            ``sprocket_speed`` [rad/s], ``sprocket_acceleration`` [rad/s^2], ``motor_torque`` [N m],
            ``link_tension`` (p,) [N] (2 lambda L), ``roller_position``, ``roller_velocity``,
            ``roller_acceleration`` (p, 2) [m, m/s, m/s^2], ``closure_residual`` [m] (max over
            links of | |r_{i+1} - r_i| - L |) and ``constraint_velocity`` [m^2/s] (max |dC_i/dt|).
        """
        qdd, lam, extras = self.solve(t, y)
        part, vel, wq = self.work[0], self.work[1], self.work[2]
        p, n = self.p, self.n
        pos = part[:, 0:2].copy()
        acc = part[:, 2:4] * qdd[:p, None] + part[:, 4:6] * qdd[p] + wq
        u = np.roll(pos, -1, axis=0) - pos
        dv = np.roll(vel, -1, axis=0) - vel
        return {
            "delta": float(y[p]),
            "chain_speed": float(math.hypot(vel[0, 0], vel[0, 1])),
            "sprocket_angle": float(y[p + 1]),
            "sprocket_speed": float(y[n + p + 1]),
            "sprocket_acceleration": float(qdd[p + 1]),
            "motor_torque": float(extras[0]),
            "link_tension": 2.0 * lam * self.pitches,
            "roller_position": pos,
            "roller_velocity": vel.copy(),
            "roller_acceleration": acc,
            "closure_residual": float(study_closure_residual(part, p, self.pitches)),
            "constraint_velocity": float(np.abs(2.0 * np.sum(u * dv, axis=1)).max()),
        }


def run_study(
    scene,
    *,
    duration,
    rtol=1e-3,
    atol=1e-3,
    max_step=1e-3,
    method="BDF",
    alpha=BAUMGARTE_ALPHA,
    beta=BAUMGARTE_BETA,
    coordinate_map="study",
    output_step=None,
    first_step=None,
    max_wall_time=math.inf,
):
    """Integrate a forward scene with the study's formulation (all p + 2 coordinates, Baumgarte).

    Parameters
    ----------
    scene : Scene or str or Path
        A forward-dynamics scene (``analysis = "forward"``), or the path of its TOML file. Its
        ``[run]`` start, initial speed and output step and its effects are used; its ``[solver]``
        section is not (the study's settings are the defaults below).
    duration : float
        Length of the run. [s]
    rtol, atol : float
        Tolerances of ``scipy.integrate.solve_ivp`` (the study's RelTol = AbsTol = 1e-3). atol is in
        the units of each state: m, m/s, rad, rad/s.
    max_step : float
        Largest step (the study's MaxStep = 1e-3). [s]
    method : str
        A ``solve_ivp`` method; "BDF" (variable order 1-5, like ode15s) by default.
    alpha, beta : float
        Baumgarte constants. [1/s]
    coordinate_map : {"study", "vibkit"}
        The study's linear map of s0 on the telescopic runs, or vibkit's C1 map (see
        :class:`StudyFormulation`).
    output_step : float, optional
        Spacing of the output times; the scene's ``run.output_step`` by default. [s]
    first_step : float, optional
        First step handed to ``solve_ivp``. [s]
    max_wall_time : float
        Wall-time budget; the run raises :class:`IntegrationError` beyond it. [s]

    Returns
    -------
    xarray.Dataset
        Dimension ``time`` [s] (and ``link``): ``delta`` [m], ``chain_speed`` [m/s],
        ``sprocket_speed`` [rad/s], ``sprocket_angle`` [rad], ``motor_torque`` [N m],
        ``link_tension`` (time, link) [N] = 2 lambda L, ``closure_residual`` [m] and
        ``constraint_velocity`` [m^2/s] (max |dC_i/dt|), with the same names and units as
        :func:`vibkit.analyses.forward.forward_dynamics`. Attrs record the formulation, alpha, beta, the
        solver's evaluations (finite-difference Jacobian columns included), Jacobians, LU
        decompositions and wall time.

    Raises
    ------
    ValueError
        A non-forward scene, or a non-positive duration, tolerance or step, or an unknown method.
    IntegrationError
        The solver failed (its message is carried) or the wall-time budget ran out.

    Notes
    -----
    The derived outputs are re-evaluated at the output states (the study's "calculos cinematicos y
    dinamicos" pass): the KKT system is solved once more at each output time.

    References
    ----------
    A. Cuevas López, Modelado y simulación de la cadena de tracción de una escalera mecánica como
    sistema multicuerpo, Proyecto Fin de Carrera, Universidad de Sevilla, 2020 (the study), chapters 5-7, eqs. 6-8 to 6-14 and 7-14;
    J. Baumgarte, Comput. Methods Appl. Mech. Eng. 1 (1972) 1-16.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if scene.analysis != "forward":
        raise ValueError(
            f"run_study needs a forward-dynamics scene, got analysis = {scene.analysis!r} in {scene.source}"
        )
    for name, value in (("duration", duration), ("rtol", rtol), ("atol", atol), ("max_step", max_step)):
        if not (isinstance(value, (int, float)) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    if method not in _SOLVE_IVP_METHODS:
        raise ValueError(f"method must be one of {', '.join(_SOLVE_IVP_METHODS)}, got {method!r}")
    run = scene.run
    dt = output_step if output_step is not None else run.output_step
    if not dt > 0:
        raise ValueError(f"output_step must be positive [s], got {dt!r}")
    model = EscalatorModel(scene)
    form = StudyFormulation(model, scene.effects, alpha=alpha, beta=beta, coordinate_map=coordinate_map)
    y0 = form.initial_state(start=run.start, speed=run.initial_speed)
    t_out = np.arange(0.0, duration + 0.5 * dt, dt)  # the grid of vibkit.analyses.forward.forward_dynamics
    from scipy.integrate import solve_ivp

    t0 = time.perf_counter()

    def fun(t, y):
        if form.evaluations % 1000 == 0 and time.perf_counter() - t0 > max_wall_time:
            raise IntegrationError(f"{method}: wall-time budget of {max_wall_time:g} s exceeded")
        return form.rhs(t, y)

    kw = {"rtol": rtol, "atol": atol, "max_step": max_step}
    if first_step:
        kw["first_step"] = first_step
    sol = solve_ivp(fun, (0.0, float(t_out[-1])), y0, method=method, t_eval=t_out, **kw)
    wall = time.perf_counter() - t0
    if not sol.success:
        raise IntegrationError(f"{method} (study formulation): {sol.message}", float(sol.t[-1]) if sol.t.size else 0.0)
    return _dataset(form, sol, wall, method, rtol, atol, max_step)


def _dataset(form, sol, wall, method, rtol, atol, max_step):
    model = form.model
    scene = model.scene
    t = sol.t
    nt = t.size
    scalars = (
        "delta",
        "chain_speed",
        "sprocket_speed",
        "sprocket_angle",
        "motor_torque",
        "closure_residual",
        "constraint_velocity",
    )
    out = {name: np.empty(nt) for name in scalars}
    tension = np.empty((nt, form.p))
    for j in range(nt):
        obs = form.observe(float(t[j]), sol.y[:, j])
        for name in scalars:
            out[name][j] = obs[name]
        tension[j] = obs["link_tension"]
    data = {name: (("time",), out[name]) for name in scalars}
    data["link_tension"] = (("time", "link"), tension)
    nominal = nominal_speed(form.effects, scene.run)
    # the sprocket's turning rate: its mesh frequency is the chain's link pass where the chain rides its teeth
    speed, f_lp = nominal, model.link_pass_frequency(nominal) if nominal else 0.0
    half = nt // 2
    if nt >= 3 and t[-1] > t[half]:
        f_lp = model.sprocket.teeth * abs(out["sprocket_angle"][-1] - out["sprocket_angle"][half])
        f_lp /= 2.0 * np.pi * (t[-1] - t[half])
        speed = f_lp * model.mean_pitch
    attrs = {
        "formulation": "study: p + 2 coordinates, Lagrange multipliers, Baumgarte stabilisation",
        "baumgarte_alpha_per_s": form.alpha,
        "baumgarte_beta_per_s": form.beta,
        "coordinate_map": form.coordinate_map,
        "chain_speed_m_s": float(speed),
        "speed_set_point_m_s": float(nominal),
        "link_pass_frequency_hz": float(f_lp),
        "closure_residual_max": float(out["closure_residual"].max()),
        "solver_method": method,
        "solver_rtol": float(rtol),
        "solver_atol": float(atol),
        "solver_max_step": float(max_step),
        "solver_evaluations": int(form.evaluations),
        "solver_jacobians": int(sol.njev),
        "solver_lu": int(sol.nlu),
        "solver_wall_time_s": float(wall),
        "effects": ", ".join(sorted(form.effects)),
    }
    coords = {"time": t, "link": np.arange(1, form.p + 1)}
    ds = make_dataset(coords, data, attrs, scene)
    ds["constraint_velocity"].attrs.update(
        {"units": "m^2/s", "long_name": "max over links of |dC_i/dt|, C_i = |r_i+1 - r_i|^2 - L^2"}
    )
    ds.attrs["history"] += "\nintegrated with the study's formulation (vibkit.analyses.reference.run_study)"
    return ds
