"""Integrators behind one interface.

``integrate(fun_kernel, y0, t_out, method=..., rtol=..., atol=...)`` advances the forward dynamics
and returns the state at the requested output times. Methods:

``"dopri5"`` (default)
    Dormand-Prince 5(4) with its 4th-order dense output, the whole step loop compiled with numba
    together with the right-hand side: no Python call per step. Adaptive explicit, high order.
    The error of the coordinates s0_1 and theta, which grow without bound, is measured against
    a fixed 1 m and 1 rad (rtol is then an absolute tolerance on them), so the accuracy of a long
    run does not loosen as the chain goes round. With ``events`` every step ends on the values of
    s0_1 where the right-hand side is not smooth (a roller on a curvature jump of the guide), and
    with ``t_events`` on given times, so no step straddles a jump (see :func:`_dopri5_chunk`).
``"rk45"``, ``"dop853"``
    scipy.integrate.solve_ivp's explicit methods (Python loop; the RHS is still compiled).
``"bdf"``, ``"radau"``, ``"lsoda"``
    scipy's implicit (stiff) methods, with a finite-difference Jacobian of the 5-state system.
``"cvode-bdf"``, ``"cvode-adams"``
    SUNDIALS CVODE through scikit-sundae (optional: ``pip install 'vibkit[sundials]'``), BDF
    (stiff) or Adams (non-stiff) multistep, dense Jacobian by differences.

Every method raises :class:`IntegrationError` (with the time and the state) when the step size
collapses, the chain cannot be closed, the right-hand side is not finite, or the run exceeds its
wall-time budget -- never a hang.
"""

from __future__ import annotations

import math
import time

import numba as nb
import numpy as np

from ..model import pitch_table
from ..model.pitch_table import empty_table, rhs
from ..model.slots import (
    COUNT_EVALUATIONS,
    COUNT_EVENT_RETRIES,
    COUNT_EVENT_STEPS,
    COUNT_LANDINGS,
    COUNT_REJECTED,
    COUNT_STEPS,
    COUNTER_NAMES,
    CTL_BREAKPOINT,
    CTL_DIRECTION,
    CTL_HAS_BREAKPOINT,
    CTL_LAST_ERROR,
    CTL_NAMES,
    CTL_REJECTED,
    CTL_WANTED_STEP,
)
from ..runtime.kernel import kernel
from ..runtime.kernel_cache import COMPILING_NOTE, kernel_cached
from ..runtime.progress import Progress

__all__ = ["integrate", "IntegrationError", "METHODS"]

METHODS = ("dopri5", "rk45", "dop853", "bdf", "radau", "lsoda", "cvode-bdf", "cvode-adams")


class IntegrationError(RuntimeError):
    """The integration could not go on; carries the solver's message, the time and the state."""

    def __init__(self, message, t=None, y=None):
        detail = ""
        if t is not None:
            detail = f" at t = {t:.6g} s"
        if y is not None:
            detail += (
                f" (state s0_1 = {y[0]:.9g} m, s0dot = {y[1]:.6g} m/s, theta = {y[2]:.6g} rad, "
                f"thetadot = {y[3]:.6g} rad/s)"
            )
        super().__init__(message + detail)
        self.t = t
        self.y = None if y is None else np.array(y)


# Dormand-Prince 5(4) tableau
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = 71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40
D1, D3, D4, D5, D6, D7 = (
    -12715105075 / 11282082432,
    87487479700 / 32700410799,
    -10690763975 / 1880347072,
    701980252875 / 199316789632,
    -1453857185 / 822651844,
    69997945 / 29380423,
)


@kernel()
def _next_crossing(s, direction, cross, p0, gap):
    """The first crossing value beyond s in ``direction`` (+1 or -1), farther than ``gap``. [m]

    ``cross`` holds the crossing values of one period ``p0`` (sorted, in [0, p0)); the result is
    an absolute coordinate (the period added as many times as s holds it).
    """
    m = math.floor(s / p0)
    r = s - m * p0
    if direction > 0:
        j = np.searchsorted(cross, r + gap, side="right")
        if j < cross.size:
            return m * p0 + cross[j]
        return (m + 1.0) * p0 + cross[0]
    j = np.searchsorted(cross, r - gap, side="left") - 1
    if j >= 0:
        return m * p0 + cross[j]
    return (m - 1.0) * p0 + cross[cross.size - 1]


@kernel()
def _time_to(dist, v, a):
    """Smallest positive h with v h + a h^2 / 2 = dist (inf if never). [s]"""
    disc = v * v + 2.0 * a * dist
    if disc < 0.0:
        return math.inf
    r = math.sqrt(disc)
    den = v + r if v >= 0.0 else v - r
    if den != 0.0:
        h = 2.0 * dist / den
        if h > 0.0:
            return h
    if a != 0.0:
        h = (-v + r) / a if a > 0.0 else (-v - r) / a
        if h > 0.0:
            return h
    return math.inf


@kernel()
def _dense_component(th, y0, y1, k1, k7, h, r5):
    r2 = y1 - y0
    r3 = h * k1 - r2
    r4 = r2 - h * k7 - r3
    return y0 + th * (r2 + (1.0 - th) * (r3 + th * (r4 + (1.0 - th) * r5)))


@kernel()
def _side(pos, has_lo, lo, has_hi, hi, direction, tiny):
    """A stage's y[0] kept on the smooth side of the breakpoints that bound the step."""
    if has_hi and (pos - hi) * direction > -tiny:
        pos = hi - direction * tiny
    if has_lo and (pos - lo) * direction < tiny:
        pos = lo + direction * tiny
    return pos


@kernel()
def _start_past(t, y, yt, k1, s_b, direction, tiny, prm, ws, ctl, counters, tb):
    """The next step starts on breakpoint s_b: remember it (``ctl[CTL_HAS_BREAKPOINT]``, ``ctl[CTL_BREAKPOINT]``, ``ctl[CTL_DIRECTION]``) and take k1, the
    right-hand side at (t, y), on its far side. Returns evaluate's status."""
    ctl[CTL_HAS_BREAKPOINT] = 1.0
    ctl[CTL_BREAKPOINT] = s_b
    ctl[CTL_DIRECTION] = direction
    for i in range(y.size):
        yt[i] = y[i]
    yt[0] = _side(yt[0], True, s_b, False, 0.0, direction, tiny)
    counters[COUNT_EVALUATIONS] += 1
    return rhs(t, yt, k1, prm, ws, False, tb)


@kernel(inline="always")
def _scale(i, a, b, rtol, atol):
    """The error scale of component ``i`` over a step from ``a`` to ``b``. Positions and angles (components 0
    and 2) grow without bound: their tolerance is taken against a fixed 1 m / 1 rad, so that the accuracy does
    not loosen over time."""
    if i == 0 or i == 2:
        return atol + rtol
    return atol + rtol * max(abs(a), abs(b))


#: a breakpoint closer than this share of the step ahead (the last step ended just short of it) is landed on
#: by :func:`_land`, one evaluation, instead of a dopri5 step of six
LAND = 0.01


@kernel()
def _land(t, y, hl, k1, k2, yt, y1, has_lo, lo, sc, direction, tiny, rtol, atol, prm, ws, tb):
    """Heun's step of ``hl`` from (t, y) with k1 = f(t, y), its stages on the near side of breakpoint
    ``sc`` (which the quadratic of y[0], exactly what Heun's step integrates, reaches at t + hl):
    y1 and k2 filled. Returns 0 when Euler's estimate of its error is within the tolerance, 2 when
    not (nothing taken), -1 where the chain cannot close."""
    m = y.size
    for i in range(m):
        yt[i] = y[i] + hl * k1[i]
    yt[0] = _side(yt[0], has_lo, lo, True, sc, direction, tiny)
    if rhs(t + hl, yt, k2, prm, ws, False, tb) != 0:
        return -1
    err = 0.0
    for i in range(m):
        y1[i] = y[i] + 0.5 * hl * (k1[i] + k2[i])
        ei = 0.5 * hl * (k2[i] - k1[i]) / _scale(i, y[i], y1[i], rtol, atol)
        err += ei * ei
    err = math.sqrt(err / m)
    return 0 if err <= 1.0 else 2


@nb.njit(cache=True, error_model="numpy", nogil=True)  # nogil: the convergence check runs two at once
def _dopri5_chunk(
    t, y, h, k1, t_stop, t_out, idx, y_out, prm, ws, rtol, atol, max_step, counters, ctl, cross, p0, gap, pause, tb
):
    """Advance from t towards t_stop, writing the dense output at t_out[idx:] <= t_stop.

    Returns (status, t, h, idx): status 0 ok, 1 closure failure, 2 step size collapse,
    3 non-finite state, 4 too many steps, 5 paused after ``pause`` steps (call again: the step
    sequence does not depend on where the pauses fall).
    ``ctl`` carries the controller's memory between calls: [previous error, last step rejected,
    step size before a breakpoint cut it, the step starts on a breakpoint, that breakpoint, its
    direction]. The step-size controller is Hairer's PI (Lund) stabilisation of DOPRI5
    (beta = 0.04). ``counters`` accumulates [steps, rejected, evaluations, breakpoint steps, steps taken again
    because they passed a breakpoint, landings].

    Breakpoints: ``cross`` holds the values of y[0] (one period ``p0``, sorted) at which the
    right-hand side is not smooth (a roller on a curvature jump of the guide, a passenger's step at
    a landing). No step straddles one. A step that would reach the next one is cut to end on it
    (predicted from the velocity and acceleration of y[0]; located on the dense output and taken
    again if it passes it by more than ``gap`` [m]); every stage of that step evaluates the
    right-hand side on the near side of the breakpoint, and every stage of the next one on the far
    side. So each step integrates a smooth function and keeps the method's order. A step that ends
    short of the breakpoint by more than ``gap`` leaves it a few microseconds ahead: Heun's step lands
    on it (:func:`_land`; one evaluation instead of six; its stages on the near side as well).
    """
    m = y.size
    k2 = np.empty(m)
    k3 = np.empty(m)
    k4 = np.empty(m)
    k5 = np.empty(m)
    k6 = np.empty(m)
    k7 = np.empty(m)
    yt = np.empty(m)
    y1 = np.empty(m)
    nev = cross.size
    taken = 0
    tiny = 1e-11  # [m] how far on its side of a breakpoint a stage is evaluated
    while t < t_stop:
        hmin = 1e-12 * max(1.0, abs(t))
        hnat = max(h, ctl[CTL_WANTED_STEP])  # the step the error controller wants, before a breakpoint cut it
        if h > max_step:
            h = max_step
        has_hi = False
        sc = 0.0
        direction = 1.0
        if nev > 0:
            v = k1[0]
            direction = 1.0 if (v > 0.0 or (v == 0.0 and k1[1] >= 0.0)) else -1.0
            if ctl[CTL_HAS_BREAKPOINT] > 0.0 and ctl[CTL_DIRECTION] != direction:
                ctl[CTL_HAS_BREAKPOINT] = 0.0  # the motion reversed: the breakpoint behind no longer bounds the step
            if ctl[CTL_HAS_BREAKPOINT] == 0.0:
                # starting on a breakpoint (at t = 0, after a time event or a reversal): take the
                # right-hand side on the far side
                s_on = _next_crossing(y[0] - 2.0 * gap * direction, direction, cross, p0, 0.0)
                if abs(y[0] - s_on) <= gap:
                    if _start_past(t, y, yt, k1, s_on, direction, tiny, prm, ws, ctl, counters, tb) != 0:
                        return 1, t, h, idx
            sc = _next_crossing(y[0], direction, cross, p0, gap)
            hc = _time_to(sc - y[0], v, k1[1])
            if hc <= LAND * hnat and t + hc < t_stop:
                # a breakpoint just ahead (the last step ended short of it): land on it with one
                # evaluation (Heun's step, its error estimated by Euler's) instead of a step of six
                st = _land(
                    t,
                    y,
                    hc,
                    k1,
                    k2,
                    yt,
                    y1,
                    ctl[CTL_HAS_BREAKPOINT] > 0.0,
                    ctl[CTL_BREAKPOINT],
                    sc,
                    direction,
                    tiny,
                    rtol,
                    atol,
                    prm,
                    ws,
                    tb,
                )
                counters[COUNT_EVALUATIONS] += 1
                if st < 0:
                    return 1, t, h, idx
                if st == 0:
                    tn = t + hc
                    while idx < t_out.size and t_out[idx] <= tn + 1e-12 * max(1.0, abs(tn)):
                        th = (t_out[idx] - t) / hc
                        for i in range(m):
                            y_out[idx, i] = y[i] + th * hc * (k1[i] + 0.5 * th * (k2[i] - k1[i]))
                        idx += 1
                    t = tn
                    for i in range(m):
                        y[i] = y1[i]
                    counters[COUNT_STEPS] += 1
                    counters[COUNT_EVENT_STEPS] += 1
                    counters[COUNT_LANDINGS] += 1
                    taken += 1
                    if _start_past(t, y, yt, k1, sc, direction, tiny, prm, ws, ctl, counters, tb) != 0:
                        return 1, t, h, idx
                    h = hnat
                    # the controller's memory as the six-evaluation step it replaces left it (an error near
                    # zero): that memory holds the steps in the backlash as short as before, and the backlash's
                    # accuracy with them (docs/explanation/performance.md, "Landed: Heun's step")
                    ctl[CTL_LAST_ERROR] = 0.0
                    ctl[CTL_WANTED_STEP] = 0.0
                    ctl[CTL_REJECTED] = 0.0
                    if taken >= pause:
                        return 5, t, h, idx
                    continue
                counters[COUNT_REJECTED] += 1
            if hc <= h:
                h = hc
                ctl[CTL_WANTED_STEP] = hnat
            # a step that ends on (or within a micrometre of) the breakpoint keeps its stages on
            # the near side of it
            if (y[0] + h * (v + 0.5 * h * k1[1]) - sc) * direction > -1e-6:
                has_hi = True
        has_lo = ctl[CTL_HAS_BREAKPOINT] > 0.0
        lo = ctl[CTL_BREAKPOINT]
        last = False
        if t + h >= t_stop:
            h = t_stop - t
            last = True
        for i in range(m):
            yt[i] = y[i] + h * A21 * k1[i]
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + h / 5, yt, k2, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        for i in range(m):
            yt[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + 0.3 * h, yt, k3, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        for i in range(m):
            yt[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + 0.8 * h, yt, k4, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        for i in range(m):
            yt[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + h * 8 / 9, yt, k5, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        for i in range(m):
            yt[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + h, yt, k6, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        for i in range(m):
            y1[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i])
            yt[i] = y1[i]
        yt[0] = _side(yt[0], has_lo, lo, has_hi, sc, direction, tiny)
        if rhs(t + h, yt, k7, prm, ws, False, tb) != 0:
            return 1, t, h, idx
        counters[COUNT_EVALUATIONS] += 6
        err = 0.0
        for i in range(m):
            sc_i = _scale(i, y[i], y1[i], rtol, atol)
            ei = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]) / sc_i
            err += ei * ei
        err = math.sqrt(err / m)
        if not math.isfinite(err):
            if h <= hmin:
                return 3, t, h, idx
            h *= 0.25
            counters[COUNT_REJECTED] += 1
            continue
        if err <= 1.0 and nev > 0:
            # did the step pass a breakpoint by more than the gap? then end it there and redo it
            s_hit = sc if has_hi else _next_crossing(y[0], direction, cross, p0, gap)
            over = (y1[0] - s_hit) * direction
            back = _next_crossing(y[0], -direction, cross, p0, gap)
            if (y1[0] - back) * direction < -gap:
                over = gap + 1.0  # moved backwards past one (a reversal within the step)
                s_hit = back
            if over > gap:
                r5 = h * (D1 * k1[0] + D3 * k3[0] + D4 * k4[0] + D5 * k5[0] + D6 * k6[0] + D7 * k7[0])
                lo_t, hi_t = 0.0, 1.0
                f_lo = y[0] - s_hit
                for _ in range(60):
                    mid = 0.5 * (lo_t + hi_t)
                    f_mid = _dense_component(mid, y[0], y1[0], k1[0], k7[0], h, r5) - s_hit
                    if (f_mid > 0.0) == (f_lo > 0.0):
                        lo_t = mid
                        f_lo = f_mid
                    else:
                        hi_t = mid
                    if (hi_t - lo_t) * h <= 1e-15 * max(1.0, abs(t)):
                        break
                counters[COUNT_REJECTED] += 1
                counters[COUNT_EVENT_RETRIES] += 1
                ctl[CTL_WANTED_STEP] = hnat
                h = max(lo_t * h, hmin)
                continue
        if err <= 1.0:
            # dense output for the output times inside (t, t + h]
            tn = t + h
            while idx < t_out.size and t_out[idx] <= tn + 1e-12 * max(1.0, abs(tn)):
                th = (t_out[idx] - t) / h
                for i in range(m):
                    r2 = y1[i] - y[i]
                    r3 = h * k1[i] - r2
                    r4 = r2 - h * k7[i] - r3
                    r5 = h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i])
                    y_out[idx, i] = y[i] + th * (r2 + (1.0 - th) * (r3 + th * (r4 + (1.0 - th) * r5)))
                idx += 1
            t = t_stop if last else tn
            for i in range(m):
                y[i] = y1[i]
                k1[i] = k7[i]
            counters[COUNT_STEPS] += 1
            taken += 1
            ctl[CTL_HAS_BREAKPOINT] = 0.0
            if has_hi and abs(y[0] - sc) <= gap:
                # on the breakpoint: the next step starts from the right-hand side on its far side
                counters[COUNT_EVENT_STEPS] += 1
                if _start_past(t, y, yt, k1, sc, direction, tiny, prm, ws, ctl, counters, tb) != 0:
                    return 1, t, h, idx
            if not last:
                e = max(err, 1e-10)
                fac = 0.9 * e ** (-0.2 + 0.75 * 0.04) * max(ctl[CTL_LAST_ERROR], 1e-4) ** 0.04
                fac = min(10.0, max(0.2, fac))
                if ctl[CTL_REJECTED] > 0.0:  # no growth right after a rejection
                    fac = min(fac, 1.0)
                h = h * fac
                if ctl[CTL_WANTED_STEP] > 0.0:
                    # the step was cut by a breakpoint, not by the error: go on with the step the
                    # controller had before the cut
                    h = max(h, ctl[CTL_WANTED_STEP])
                ctl[CTL_LAST_ERROR] = err
            else:
                h = hnat  # cut to end on t_stop: the next call goes on with the step it had
            ctl[CTL_WANTED_STEP] = 0.0
            ctl[CTL_REJECTED] = 0.0
        else:
            counters[COUNT_REJECTED] += 1
            h = h * max(0.2, 0.9 * err ** (-0.2 + 0.75 * 0.04))
            ctl[CTL_REJECTED] = 1.0
            ctl[CTL_WANTED_STEP] = 0.0
            if h < hmin:
                return 2, t, h, idx
        if counters[COUNT_STEPS] + counters[COUNT_REJECTED] > 50_000_000:
            return 4, t, h, idx
        if taken >= pause:
            return 5, t, h, idx  # pause: lets the caller check its wall-time budget and draw progress
    return 0, t, h, idx


#: a wall-time budget under this cannot cover compiling the kernels after an install (64-70 CPU-s on two cores);
#: such a budget on a machine without them compiled is exceeded before the first step [s]
MIN_COLD_BUDGET_S = 10.0


def _cold(method) -> bool:
    """Whether the right-hand side (and the dopri5 loop) is not compiled and cached on this machine yet."""
    cold = not kernel_cached(pitch_table.__file__, "rhs")
    if method == "dopri5":
        cold = cold or not kernel_cached(__file__, "_dopri5_chunk")
    return cold


def _compile_note(cold):
    """What the progress bar says first when the kernels are not compiled yet."""
    return COMPILING_NOTE if cold else ""


def _closure_message(status):
    return {
        1: "the chain could not be closed (delta left the tensioner's travel)",
        2: "step size collapsed",
        3: "the state became non-finite",
        4: "too many steps",
    }[status]


def integrate(
    prm,
    ws,
    y0,
    t_out,
    *,
    method="dopri5",
    rtol=1e-6,
    atol=1e-9,
    max_step=math.inf,
    first_step=None,
    max_wall_time=math.inf,
    progress=True,
    label="forward dynamics",
    events=None,
    event_gap=1e-6,
    t_events=None,
    table=None,
):
    """State at the output times ``t_out`` (increasing, starting at 0) of the forward dynamics.

    Parameters
    ----------
    events : (ndarray, float), optional
        dopri5 only: the sorted values of y[0] in one period where the right-hand side is not
        smooth, and the period [m] (:meth:`vibkit.model.chain.Chain.crossing_table`, P0).
    event_gap : float
        How far from such a value a step may end and count as ending on it. [m]
    t_events : array_like, optional
        dopri5 only: times at which the right-hand side jumps; steps end on them. [s]
    table : tuple, optional
        The chain's configuration over one pitch (:func:`vibkit.model.pitch_table.build_table`):
        the right-hand side reads the closure from it instead of solving it.

    Returns
    -------
    y_out : ndarray (len(t_out), 5)
    stats : dict
        ``steps``, ``rejected``, ``evaluations``, ``wall_time_s``, ``method``, and for dopri5
        ``event_steps`` (steps that ended on a breakpoint), ``event_retries`` (steps taken again because
        they passed one) and ``landings`` (Heun's steps onto one, counted among the steps).
    """
    tb = empty_table() if table is None else table
    method = method.lower()
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    t_out = np.ascontiguousarray(t_out, dtype=float)
    y = np.array(y0, dtype=float)
    y_out = np.full((t_out.size, y.size), np.nan)
    t0 = time.perf_counter()
    cold = _cold(method)
    if cold and max_wall_time < MIN_COLD_BUDGET_S:
        # the budget counts from here, the compile included: a short one would only be found exceeded after a minute
        raise IntegrationError(
            f"{method}: wall-time budget of {max_wall_time:g} s exceeded before the first step, by compiling the "
            "model's kernels for this machine (about a minute, once, then cached: run once without the budget)",
            0.0,
            y,
        )
    bar = Progress(t_out[-1], label, enabled=progress, note=_compile_note(cold) if progress else "")
    if method == "dopri5":
        counters = np.zeros(len(COUNTER_NAMES), dtype=np.int64)
        ctl = np.zeros(len(CTL_NAMES))
        ctl[CTL_LAST_ERROR] = 1e-4
        ctl[CTL_DIRECTION] = 1.0
        cross = np.ascontiguousarray(events[0], dtype=float) if events is not None else np.zeros(0)
        period = float(events[1]) if events is not None else 1.0
        # times at which the right-hand side jumps (passengers by time): steps end on them, the
        # last output time among them so that a run's steps do not depend on its length
        stops = np.unique(np.concatenate([np.asarray(t_events if t_events is not None else [], dtype=float)]))
        stops = stops[(stops > 0.0) & (stops < t_out[-1])]
        stops = np.append(stops, t_out[-1])
        k1 = np.empty_like(y)
        if rhs(0.0, y, k1, prm, ws, False, tb) != 0:
            raise IntegrationError(_closure_message(1), 0.0, y)
        y_out[0] = y
        idx = 1
        t = 0.0
        h = first_step or min(1e-3, max_step)
        js = 0
        while t < t_out[-1]:
            while stops[js] <= t:
                js += 1
            try:
                # pauses every 256 steps for the wall-time budget and the progress bar; the steps
                # themselves never depend on where the pauses fall, nor on the output times
                status, t, h, idx = _dopri5_chunk(
                    t,
                    y,
                    h,
                    k1,
                    stops[js],
                    t_out,
                    idx,
                    y_out,
                    prm,
                    ws,
                    rtol,
                    atol,
                    max_step,
                    counters,
                    ctl,
                    cross,
                    period,
                    event_gap,
                    256,
                    tb,
                )
                if status == 0 and t < t_out[-1]:
                    # a time event: the right-hand side changes here; start again from its new value
                    if rhs(t, y, k1, prm, ws, False, tb) != 0:
                        raise IntegrationError(_closure_message(1), t, y)
                    counters[COUNT_EVALUATIONS] += 1
            except (ZeroDivisionError, FloatingPointError, ValueError) as exc:  # a degenerate state
                bar.close()
                raise IntegrationError(f"dopri5: the state became degenerate ({exc})", t, y) from None
            if status not in (0, 5):
                bar.close()
                raise IntegrationError(f"dopri5: {_closure_message(status)}", t, y)
            bar.update(t)
            if time.perf_counter() - t0 > max_wall_time:
                bar.close()
                raise IntegrationError(f"dopri5: wall-time budget of {max_wall_time:g} s exceeded", t, y)
        bar.close()
        stats = {
            "steps": int(counters[COUNT_STEPS]),
            "rejected": int(counters[COUNT_REJECTED]),
            "evaluations": int(counters[COUNT_EVALUATIONS] + 1),
            "event_steps": int(counters[COUNT_EVENT_STEPS]),
            "event_retries": int(counters[COUNT_EVENT_RETRIES]),
            "landings": int(counters[COUNT_LANDINGS]),
        }
    elif method.startswith("cvode"):
        try:
            from sksundae.cvode import CVODE
        except ImportError:
            raise ValueError(f"method {method!r} needs scikit-sundae: pip install 'vibkit[sundials]'") from None
        dy = np.empty_like(y)
        nev = [0]
        failure = []

        def cvode_rhs(t, yy, yp):
            nev[0] += 1
            if nev[0] % 2000 == 0:
                bar.update(t)
                if time.perf_counter() - t0 > max_wall_time:
                    failure.append(
                        IntegrationError(f"{method}: wall-time budget of {max_wall_time:g} s exceeded", t, yy)
                    )
                    yp[:] = np.nan
                    return
            if rhs(t, np.ascontiguousarray(yy), dy, prm, ws, False, tb) != 0:
                failure.append(IntegrationError(f"{method}: {_closure_message(1)}", t, yy))
                yp[:] = np.nan
                return
            yp[:] = dy

        opts = {
            "method": "BDF" if method == "cvode-bdf" else "Adams",
            "rtol": rtol,
            "atol": atol,
            "max_num_steps": 1_000_000,
        }
        if math.isfinite(max_step):
            opts["max_step"] = max_step
        if first_step:
            opts["first_step"] = first_step
        sol = CVODE(cvode_rhs, **opts).solve(t_out, y)
        bar.close()
        if failure:
            raise failure[0]
        if not sol.success:
            ylast = sol.y[-1] if len(sol.y) else y
            raise IntegrationError(f"{method}: {sol.message}", float(sol.t[-1]) if len(sol.t) else 0.0, ylast)
        y_out[:] = sol.y
        stats = {"steps": int(getattr(sol, "nsteps", 0) or 0), "rejected": 0, "evaluations": int(nev[0])}
    else:
        from scipy.integrate import solve_ivp

        dy = np.empty_like(y)
        nev = [0]

        def fun(t, yy):
            nev[0] += 1
            if nev[0] % 2000 == 0:
                bar.update(t)
                if time.perf_counter() - t0 > max_wall_time:
                    raise IntegrationError(f"{method}: wall-time budget of {max_wall_time:g} s exceeded", t, yy)
            if rhs(t, np.ascontiguousarray(yy), dy, prm, ws, False, tb) != 0:
                raise IntegrationError(f"{method}: {_closure_message(1)}", t, yy)
            return dy.copy()

        kw = {"rtol": rtol, "atol": atol, "max_step": max_step}
        if first_step:
            kw["first_step"] = first_step
        sol = solve_ivp(
            fun,
            (0.0, t_out[-1]),
            y,
            method={"rk45": "RK45", "dop853": "DOP853", "bdf": "BDF", "radau": "Radau", "lsoda": "LSODA"}[method],
            t_eval=t_out,
            **kw,
        )
        bar.close()
        if not sol.success:
            ylast = sol.y[:, -1] if sol.y.size else y
            tlast = float(sol.t[-1]) if sol.t.size else 0.0
            raise IntegrationError(f"{method}: {sol.message}", tlast, ylast)
        y_out[:] = sol.y.T
        stats = {"steps": int(sol.t.size), "rejected": 0, "evaluations": int(sol.nfev)}
    stats["wall_time_s"] = time.perf_counter() - t0
    stats["method"] = method
    return y_out, stats
