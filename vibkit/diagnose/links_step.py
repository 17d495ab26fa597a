"""Which link is worn, from a step accelerometer: each link-pass cycle against its neighbours.

A step rides the chain, so its acceleration is first its own trip round the loop (the curves it rides
through, the roller meeting a tooth), 0.015 m/s^2 r.m.s. on the study's escalator, which a 1 mm worn link
changes by about 0.004.  No model predicts that trip to the 0.004; but the trip changes slowly from one
link-pass cycle to the next, and a worn link passing the sprocket changes two or three cycles.  So each
cycle of the loops' mean is compared with its eight neighbours, which takes the trip out, and a template of
the worn link's change (from the escalator's scene) is fitted at every cycle
(``benchmarks/bench_links_step.py`` measured the approach).

The scene gives, for one step of a healthy chain and one with a worn link, what the recording cannot:

- the *blind* cycles, where the healthy step's own trip changes from cycle to cycle as much as a worn
  link would (the ends of the curves): a link that passes the sprocket while the step is there cannot be
  seen from that step, and is reported as not seen;
- the template, and the link each cycle shows;
- the healthy step's own residual at every cycle, which sets the threshold with the noise.

Every step of a healthy chain makes the same trip, so the recording is placed on the scene's loop by its
trip (a cross-correlation over the cycles), whichever step carries the accelerometer.  Link numbers
count, in the order the links pass, from the step's own link (link 1: the link from the roller that
carries the accelerometer to the one behind it), or from a marked link (``marker_s``: when it passed over
the top of the lower head, where the tensioner's numbers count from).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal
import scipy.stats
from scipy import optimize

__all__ = ["StepScan", "StepView", "place_on_loop", "scan_step", "step_view"]

#: samples per link-pass cycle
SAMPLES = 16
#: cycles on each side that a cycle is compared with
AROUND = 4
#: the cycles (from, to) around a link's pass of the sprocket that its template spans
WINDOW = (-1, 3)
#: a cycle is blind where the healthy step's own deviation from its neighbours (r.m.s.) exceeds this fraction of
#: the deviation of a 1 mm worn link at its largest cycle (0.5 of 2.5 mm/s^2 on the study's escalator)
BLIND_FRACTION = 0.2
#: the step's signal is low-passed at this many link-pass harmonics (zero phase)
HARMONICS = 4
#: excess pitch of the template's simulated worn link [m]
TEMPLATE_EXCESS_M = 1e-3
#: a cycle shows a worn link's change where it is at least this fraction of the largest (both runs)
EVENT_FRACTION = 0.2
#: the loop period is searched within this fraction of the one the link-pass frequency gives
LOOP_SEARCH = 0.01
#: a link whose change falls less than this share (sum of squares) on cycles that are not blind is not seen
MIN_SEEN = 0.5
#: at most this many links are flagged in one recording
MAX_FLAGS = 10
#: once a link is flagged, the links whose template overlaps its own more than this (cosine) are not flagged: two
#: worn links that close read as one
MAX_OVERLAP = 0.1
#: nor the links this close to it (a flagged link's change departs from the template, and what is left fits a
#: neighbour two links away at half a millimetre: measured on link 70 from step 20)
NEAR = 3
#: every loop of the recording, on the clock that follows the speed, must correlate with the scene's trip this well
MIN_LOOP_CORRELATION = 0.9
#: the speed's wander is followed within this many link-pass cycles of the clock at the loop period
FOLLOW_CYCLES = 3
#: and each next place within this many cycles of what the places before it predict
FOLLOW_NEXT = 1.5
#: the wander is matched on the trip below this order of the link pass (the curves, not the link pass)
SLOW_ORDER = 0.5
#: half the span of each place where the wander is matched, at least [cycles]
LANDMARK_HALF = 8.0
#: loops of the scene's runs after one loop of settling
VIEW_LOOPS = 2
#: the recording's trip must correlate with the scene's at least this well to be placed on its loop
MIN_TRIP_CORRELATION = 0.5


def lowpassed(x, fs, f_lp):
    """``x`` low-passed at ``HARMONICS`` link-pass harmonics (4th-order Butterworth, zero phase)."""
    return lowpassed_at(x, fs, HARMONICS * f_lp)


def lowpassed_at(x, fs, cutoff):
    """``x`` low-passed at ``cutoff`` [Hz] (4th-order Butterworth, zero phase)."""
    cutoff = min(cutoff, 0.45 * fs)
    sos = scipy.signal.butter(4, cutoff, fs=fs, output="sos")
    return scipy.signal.sosfiltfilt(sos, np.asarray(x, dtype=float), axis=-1)


def loop_period(y, fs, n, f_lp):
    """The chain's loop period in ``y`` (a step's signal, low-passed): the lag near ``k n / f_lp`` (``k`` the most whole
    loops the record holds beside one loop) at which the record best matches itself, over ``k``. [s]"""
    y = np.asarray(y, dtype=float) - np.mean(y)
    loop = n / float(f_lp)
    k = max(1, int((y.size / fs - loop) // loop))
    centre = k * loop * fs
    lags = np.arange(int(centre * (1 - LOOP_SEARCH)), int(centre * (1 + LOOP_SEARCH)) + 2)
    lags = lags[lags < y.size - 1]
    score = np.array([np.dot(y[:-lag], y[lag:]) / (y.size - lag) for lag in lags])
    i = int(np.argmax(score))
    if 0 < i < score.size - 1:  # parabola through the peak and its neighbours
        a, b, c = score[i - 1 : i + 2]
        den = a - 2 * b + c
        frac = 0.5 * (a - c) / den if den < 0 else 0.0
    else:
        frac = 0.0
    return (lags[i] + frac) / fs / k


def cycles(x, fs, f_lp, n, offset=0.0):
    """The step signal, low-passed, on ``SAMPLES`` points per link-pass cycle of a clock that runs at the chain's own
    loop period (:func:`loop_period`), whole loops from ``offset`` cycles after the first sample: ``(loops, n,
    SAMPLES)``, the time each cycle starts ``(loops, n)`` [s] and the link-pass frequency of the clock [Hz].

    A step's own link-pass phase is no clock: it shifts by part of a cycle wherever the step rides a curve (its
    loops came out 18 mm/s^2 r.m.s. apart on the study's escalator, against 1 by the sprocket's angle)."""
    y = lowpassed(x, fs, f_lp)
    f = n / loop_period(y, fs, n, f_lp)
    t = np.arange(y.size) / fs
    loops = int((t[-1] * f - offset) // n)
    tg = (offset + np.arange(loops * n * SAMPLES) / SAMPLES) / f
    m = np.interp(tg, t, y).reshape(loops, n, SAMPLES)
    return m, tg[::SAMPLES].reshape(loops, n), f


@functools.lru_cache(maxsize=8)
def _neighbours(n, skip):
    """Weights ``(n, n)``: each cycle minus the mean of its ``AROUND`` neighbours on each side that are not in
    ``skip`` (a tuple of booleans; all of them where every neighbour is skipped), wrapped round the loop."""
    skip = np.asarray(skip, dtype=bool)
    w = np.eye(n)
    for c in range(n):
        around = [(c + j) % n for j in range(-AROUND, AROUND + 1) if j != 0]
        kept = [k for k in around if not skip[k]] or around
        w[c, kept] -= 1.0 / len(kept)
    return w


def deviation(m, skip):
    """Each cycle of ``m`` (``(..., n, SAMPLES)``) minus the mean of its neighbours that are not blind."""
    w = _neighbours(m.shape[-2], tuple(bool(s) for s in skip))
    return np.einsum("ij,...jk->...ik", w, m)


@dataclass(frozen=True)
class StepView:
    """What a scene says one step sees of its chain (:func:`step_view`).

    Arrays by cycle are in the frame of the scene's run: cycle 0 is the first whole link-pass cycle of the
    step's signal after one loop of settling.

    Attributes
    ----------
    n_links : int
    trip : ndarray (n_links, SAMPLES)
        The healthy step's mean loop. [m/s^2]
    blind_cycle : ndarray of bool (n_links,)
        Cycles where the healthy step's own deviation from its neighbours is as large as a worn link's.
    template : ndarray (n_links, n_links, SAMPLES)
        Row ``w - 1``: what scene link ``w`` one metre longer changes in the step's deviation from its
        neighbours, on the cycles that are not blind (zero on those). [m/s^2 / m]
    residual : ndarray (n_links,)
        The healthy step's own fit of each row (noise-free), which a healthy recording carries. [m]
    seen : ndarray (n_links,)
        The share of each link's change (sum of squares) that falls on cycles that are not blind.
    step_link : int
        The scene's link of the step that carries the accelerometer (from its roller to the next).
    lower_head_link : ndarray of int (n_links,)
        The scene's link going over the top of the lower head in the middle of each cycle.
    events : int
        Where a worn link shows: the number of separate groups of cycles (its passes of the sprocket and of
        the lower head, as far as they show).
    """

    n_links: int
    trip: np.ndarray
    blind_cycle: np.ndarray
    template: np.ndarray
    residual: np.ndarray
    seen: np.ndarray
    step_link: int
    lower_head_link: np.ndarray
    events: int


def _run(scene, speed, fs, worn):
    """The step's loop mean after one loop of settling (link ``worn`` ``TEMPLATE_EXCESS_M`` longer, or healthy), and
    the links passed on the sprocket since the scene's start in the middle of each cycle of its first loop."""
    from ..analyses.simulation import simulate

    n, pitch = scene.chain.n_rollers, scene.chain.link_pitch
    f_lp = speed / pitch
    settle = n / f_lp + 5.0
    duration = settle + (VIEW_LOOPS * n + 4) / f_lp
    chain = scene.chain
    if worn is not None:
        chain = dataclasses.replace(chain, worn_links=((int(worn), pitch + TEMPLATE_EXCESS_M),))
    effects = dict(scene.effects)
    if "motor" in effects:
        effects["motor"] = dataclasses.replace(effects["motor"], speed=float(speed))
    step = scene.outputs.get("step_accelerometer") or 1
    outputs = dict(scene.outputs, variables=("accel_step", "sprocket_angle"), step_accelerometer=step)
    sc = dataclasses.replace(scene, chain=chain, effects=effects, outputs=outputs).with_solver(closure="runs")
    ds = simulate(sc, duration=duration, progress=False)
    t = ds.time.values
    tx = np.arange(settle, t[-1], 1.0 / fs)
    m, start, _ = cycles(np.interp(tx, t, ds.accel_step.values), fs, f_lp, n)
    mid = start[0] + 0.5 / f_lp
    theta = ds.sprocket_angle.values
    passed = scene.sprocket.teeth * np.abs(np.interp(mid, t, theta) - theta[0]) / (2 * np.pi)
    return m[:VIEW_LOOPS].mean(axis=0), passed, int(step)


def _median_deviation(m):
    """Each cycle of ``m`` ``(n, SAMPLES)`` minus the median of its ``AROUND`` neighbours on each side: where the trip
    changes slowly the median follows it, so only the cycles at a curve's ends stand out."""
    n = m.shape[0]
    idx = np.array([[(c + j) % n for j in range(-AROUND, AROUND + 1) if j != 0] for c in range(n)])
    return m - np.median(m[idx], axis=1)


def _size(d):
    """r.m.s. of each cycle of ``d`` ``(n, SAMPLES)``."""
    return np.sqrt(np.mean(d * d, axis=1))


def _dilate(mask):
    """``mask`` (n,) widened to the cycles around each (``WINDOW``), round the loop."""
    return np.any([np.roll(mask, j) for j in range(-WINDOW[1] + 1, 1 - WINDOW[0])], axis=0)


@functools.lru_cache(maxsize=8)
def step_view(scene_path, speed, fs):
    """What a step of the scene's escalator sees of its chain at ``speed`` [m/s], sampled at ``fs`` [Hz].

    Simulates the scene (run-by-run closure) healthy and with one link ``TEMPLATE_EXCESS_M`` longer, three
    times: two links half a loop apart show where a worn link's change is (it moves one cycle per link, the
    step's own trip does not), and a third link, whose change falls where the step is on straight track, gives
    the template.  Cached per scene, speed and rate.
    """
    from ..model.escalator import EscalatorModel
    from ..model.scene import load_scene

    scene = load_scene(scene_path)
    if scene.analysis != "forward" or scene.run.start != 0.0:
        raise ValueError(
            f"{scene_path}: a step's view of the chain needs a forward scene that starts with roller 1 at the top "
            "of the lower head ([run] start = 0), so that its links can be numbered"
        )
    n = scene.chain.n_rollers
    none = np.zeros(n, bool)
    healthy, passed, step = _run(scene, speed, fs, None)
    h0 = deviation(healthy, none)
    level = _size(_median_deviation(healthy))
    # links pass in decreasing number, one a cycle: link g + s shows s cycles before link g; the trip stays put
    g1, s = 1, n // 3  # not half a loop: the trip's curves come back about half a loop apart
    e1 = _size(deviation(_run(scene, speed, fs, g1)[0], none) - h0)
    e2 = _size(deviation(_run(scene, speed, fs, g1 + s)[0], none) - h0)
    both = np.minimum(e1, np.roll(e2, s))
    events = both > EVENT_FRACTION * both.max()
    blind_cycle = level > BLIND_FRACTION * float(e1[events].max())
    # the template's link: the shift that puts every event's cycles (and the neighbours they are compared with)
    # furthest from a blind cycle
    reach = _dilate(events)
    clear = np.array([_clearance(np.roll(reach, k), blind_cycle) for k in range(n)])
    k = int(np.argmax(clear))
    w3 = (g1 - 1 - k) % n + 1
    worn, _, _ = _run(scene, speed, fs, w3)
    change = (deviation(worn, blind_cycle) - deviation(healthy, blind_cycle)) / TEMPLATE_EXCESS_M
    change = change * np.roll(reach, k)[:, None]
    h = deviation(healthy, blind_cycle)
    rows = np.empty((n, n, SAMPLES))
    for w in range(1, n + 1):
        rows[w - 1] = np.roll(change, -(w - w3), axis=0)
    full = np.sum(rows * rows, axis=(1, 2))
    rows[:, blind_cycle] = 0.0
    kept = np.sum(rows * rows, axis=(1, 2))
    rows[kept < MIN_SEEN * full] = 0.0  # mostly blind: the fit would rest on what is left of its change
    kept = np.sum(rows * rows, axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        residual = np.einsum("wck,ck->w", rows, h) / kept
    roller = int(EscalatorModel(scene).step_rollers(step)[1]) + 1
    labels, count = _groups(events)
    return StepView(
        n_links=n,
        trip=healthy,
        blind_cycle=blind_cycle,
        template=rows,
        residual=np.where(kept > 0, residual, np.nan),
        seen=kept / full,
        step_link=roller,
        lower_head_link=(-1 - np.floor(passed)).astype(int) % n + 1,
        events=count,
    )


def _clearance(reach, blind):
    """Cycles from the nearest blind cycle to the nearest cycle of ``reach`` (0 where they meet)."""
    n = reach.size
    if not blind.any():
        return n
    idx = np.flatnonzero(blind)
    dist = np.min(np.abs(((np.arange(n)[:, None] - idx[None, :]) + n // 2) % n - n // 2), axis=1)
    return int(dist[reach].min()) if reach.any() else 0


def _groups(mask):
    """Separate runs of True round the loop: (labels, count)."""
    n = mask.size
    starts = [c for c in range(n) if mask[c] and not mask[c - 1]]
    return starts, len(starts) if not mask.all() else 1


@dataclass(frozen=True)
class StepScan:
    """Result of :func:`scan_step`. Arrays by scene link ``w`` (row ``w - 1``).

    Attributes
    ----------
    correlation : float
        Of the recording's worst loop with the scene's trip, so placed.
    loops : int
    statistic : ndarray (n,)
        Each link's fit squared over its variance (NaN where the link is not seen).
    threshold : float
        Of the largest statistic, for the false alarm asked.
    excess_m, sigma_m : ndarray (n,)
        Each link's fitted excess pitch and its standard deviation. [m]
    per_loop_m : ndarray (loops, n)
        Each loop's own fit. [m]
    cycle_start_s : ndarray (loops, n)
        When each of the recording's cycles starts, by the view's cycle. [s]
    dof : float
    flagged : tuple of int
        Scene links flagged, largest first; each after the changes of those before it were taken out.
    """

    correlation: float
    loops: int
    statistic: np.ndarray
    threshold: float
    excess_m: np.ndarray
    sigma_m: np.ndarray
    per_loop_m: np.ndarray
    cycle_start_s: np.ndarray
    dof: float
    flagged: tuple = ()


def follow(x, fs, f_lp, view):
    """The recording's clock in the view's cycles: ``(y, psi)``, the low-passed signal and the view's cycle (unwrapped)
    at every sample.

    First a clock at the chain's loop period (:func:`loop_period`), placed on the view's loop by the slow part of
    the trip (:func:`place_on_loop`); then the speed's wander: the recording near every cycle where the trip is
    distinctive (the view's blind cycles: the curves' ends), in time order, is matched with the trip within
    ``FOLLOW_CYCLES`` cycles (the first) or ``FOLLOW_NEXT`` of the one before, and the lags found are interpolated
    between those places (seconds apart; a speed controller's wander is slower)."""
    n = view.n_links
    y = lowpassed(x, fs, f_lp)
    f = n / loop_period(y, fs, n, f_lp)
    t = np.arange(y.size) / fs
    loops = int(t[-1] * f // n)
    if loops < 1:
        raise ValueError("the step recording covers less than one whole loop; a link map needs 2")
    # the trip's slow part (below half the link-pass frequency: the curves, not the link pass, which repeats every
    # cycle and would let a lag of whole cycles match as well, and which a clock a little off smears)
    spec = np.fft.rfft(view.trip.ravel())
    spec[int(SLOW_ORDER * n) :] = 0.0
    slow = np.fft.irfft(spec, n * SAMPLES)
    ys = lowpassed_at(y, fs, SLOW_ORDER * f)
    grid = np.arange(loops * n * SAMPLES) / SAMPLES / f
    mean = np.interp(grid, t, ys).reshape(loops, n, SAMPLES).mean(axis=0)
    lag, _ = place_on_loop(mean, slow.reshape(n, SAMPLES))
    psi = f * t + lag
    slow = np.append(slow, slow[0])

    full = np.append(view.trip.ravel(), view.trip.ravel()[0])

    def match(signal, model, where, steps):
        """The correlation of ``signal`` with the periodic ``model`` at view cycles ``where + d`` for every ``d``."""
        seg = signal - signal.mean()
        out = np.empty(steps.size)
        for i, d in enumerate(steps):
            mod = np.interp(((where + d) % n) * SAMPLES, np.arange(model.size), model)
            mod = mod - mod.mean()
            out[i] = float(seg @ mod) / math.sqrt(float(seg @ seg) * float(mod @ mod) + 1e-300)
        return out

    places = []  # (time, samples) of every pass of a distinctive part of the trip, in time order
    for start, stop in _merged(_runs(view.blind_cycle), LANDMARK_HALF):
        mid, half = 0.5 * (start + stop), max(0.5 * (stop - start) + 2.0, LANDMARK_HALF)
        for k in range(int(np.floor((psi[0] - mid) / n)), int(np.ceil((psi[-1] - mid) / n)) + 1):
            near = np.abs(psi - (mid + k * n)) <= half
            if np.count_nonzero(near) >= 2 * half * fs / f * 0.9:  # not cut by the record's ends
                places.append((float(np.mean(t[near])), near))
    places.sort(key=lambda p: p[0])
    knots_t, knots_lag = [], []
    fine = np.arange(-SAMPLES // 2, SAMPLES // 2 + 1) / SAMPLES
    for when, near in places:
        # each place searched around the lag the places before it predict (the wander is slow): whole cycles from
        # the slow trip, then the lag within half a cycle of it from the whole signal
        guess = knots_lag[-1] if knots_lag else 0.0
        reach = FOLLOW_CYCLES if not knots_t else FOLLOW_NEXT
        coarse = round(guess * SAMPLES) / SAMPLES + np.arange(-reach * SAMPLES, reach * SAMPLES + 1) / SAMPLES
        slow_scores = match(ys[near], slow, psi[near], coarse)
        b = int(np.argmax(slow_scores))
        if slow_scores[b] < MIN_TRIP_CORRELATION or b in (0, coarse.size - 1):
            continue  # not the trip there (noise, a passenger) or beyond the search: no knot
        scores = match(y[near], full, psi[near], coarse[b] + fine)
        j = int(np.argmax(scores))
        frac = 0.0
        if 0 < j < fine.size - 1:
            lo, mi, hi = scores[j - 1 : j + 2]
            den = lo - 2 * mi + hi
            frac = 0.5 * (lo - hi) / den / SAMPLES if den < 0 else 0.0
        knots_t.append(when)
        knots_lag.append(coarse[b] + fine[j] + frac)
    if knots_t:
        order = np.argsort(knots_t)
        psi = psi + np.interp(t, np.asarray(knots_t)[order], np.asarray(knots_lag)[order])
    return y, np.maximum.accumulate(psi)


def _merged(runs, gap):
    """``runs`` (start, stop) with those less than ``gap`` cycles apart joined (sorted by start; not across the
    loop's end)."""
    out = []
    for start, stop in sorted(runs):
        if out and start - out[-1][1] < gap:
            out[-1] = (out[-1][0], max(out[-1][1], stop))
        else:
            out.append((start, stop))
    return out


def _runs(mask):
    """(start, stop) of each run of True in ``mask`` round the loop, in cycles (``stop`` past the last; a run over
    the loop's end has ``stop`` above ``n``)."""
    n = mask.size
    if mask.all() or not mask.any():
        return []
    first = int(np.flatnonzero(~mask)[0])  # start the walk on a cycle outside every run
    out, start = [], None
    for c in range(first, first + n + 1):
        on = bool(mask[c % n]) and c < first + n
        if on and start is None:
            start = c
        elif not on and start is not None:
            out.append((start % n, start % n + (c - start)))
            start = None
    return out


def scan_step(x, fs, f_lp, view, *, false_alarm=1e-2):
    """Fit every link's change in the step recording ``x`` [m/s^2], placed on ``view``'s loop by its trip."""
    n = view.n_links
    y, psi = follow(x, fs, f_lp, view)
    t = np.arange(y.size) / fs
    first = int(math.ceil(psi[0]))
    loops = int((psi[-1] - first) // n)
    if loops < 2:
        raise ValueError(f"the step recording covers {loops} whole loop(s); a link map needs 2")
    grid = first + np.arange(loops * n * SAMPLES) / SAMPLES
    tg = np.interp(grid, psi, t)
    # row v of axis 1: the view's cycle v
    m = np.roll(np.interp(tg, t, y).reshape(loops, n, SAMPLES), first, axis=1)
    start = np.roll(tg[::SAMPLES].reshape(loops, n), first, axis=1)
    b = view.trip - view.trip.mean()
    each = [float(np.sum((x - x.mean()) * b) / math.sqrt(np.sum((x - x.mean()) ** 2) * np.sum(b * b))) for x in m]
    corr = min(each)
    if corr < MIN_TRIP_CORRELATION:
        raise ValueError(
            f"the step's trip correlates with the scene's at {corr:.2f} (at least {MIN_TRIP_CORRELATION} needed): "
            "the recording is not a step of this scene's escalator at this speed"
        )
    if corr < MIN_LOOP_CORRELATION:
        raise ValueError(
            f"the step's trip follows the scene's at {corr:.2f} in its worst loop (at least {MIN_LOOP_CORRELATION} "
            "needed): the speed wandered faster than the step's clock follows it (a passenger boarding, a change "
            "of speed); record at a steady speed, or record the tensioner's displacement"
        )
    dev = deviation(m, view.blind_cycle)  # (loops, n, SAMPLES)
    kept = np.sum(view.template**2, axis=(1, 2))
    seen = kept > 0
    safe = np.where(seen, kept, 1.0)

    def fits(d):
        return np.einsum("wck,lck->lw", view.template, d) / safe  # (loops, n): each loop's excess [m]

    fit = fits(dev)
    # the fit's noise from its scatter over the loops, pooled by the median over the links seen (scaled to the
    # mean of a chi-square with loops - 1 degrees of freedom) and by each link's own template norm
    scaled = np.var(fit[:, seen], axis=0, ddof=1) * kept[seen]
    var_unit = float(np.median(scaled)) / scipy.stats.chi2.median(loops - 1) * (loops - 1)
    var = np.where(seen, var_unit / safe, np.nan) / loops
    dof = max(1.0, 0.5 * (loops - 1) * np.count_nonzero(seen))
    lam = np.where(seen, view.residual**2 / var, 0.0)
    threshold = _threshold(lam[seen], dof, false_alarm)
    mean = fit.mean(axis=0)
    stat = np.where(seen, mean**2 / var, np.nan)
    excess, per_loop = np.where(seen, mean, np.nan), np.where(seen, fit, np.nan)
    # a worn link's change fits its neighbours' templates too (they overlap by all but a cycle): the largest is
    # flagged, its fitted change taken out of every loop, and the rest fitted again, until none passes
    # (what is left of it where the change departs from the template is not flagged: the links whose templates
    # overlap the flagged one's, and its near neighbours, are not tested again)
    flat = view.template.reshape(n, -1)
    overlap = np.abs(flat @ flat.T) / np.sqrt(np.outer(safe, safe))
    flagged, left, work, out = [], stat.copy(), dev, ~seen
    while len(flagged) < MAX_FLAGS and np.any(left[~out] > threshold):
        w = int(np.nanargmax(np.where(out, np.nan, left)))
        flagged.append(w + 1)
        excess[w], per_loop[:, w] = mean[w], fit[:, w]
        work = work - fit[:, w][:, None, None] * view.template[w][None]
        fit = fits(work)
        mean = fit.mean(axis=0)
        left = np.where(seen, mean**2 / var, np.nan)
        near = np.abs((np.arange(n) - w + n // 2) % n - n // 2) <= NEAR
        out = out | (overlap[w] > MAX_OVERLAP) | near
    return StepScan(
        correlation=corr,
        loops=loops,
        statistic=stat,
        threshold=threshold,
        excess_m=excess,
        sigma_m=np.sqrt(var),
        per_loop_m=per_loop,
        cycle_start_s=start,
        dof=dof,
        flagged=tuple(flagged),
    )


def place_on_loop(mean, trip):
    """Where the recording's mean loop ``(n, SAMPLES)`` (from phase 0 of its clock) lines up with the scene's trip:
    ``(lag, correlation)``, the recording's phase plus ``lag`` being the trip's cycle. [cycles], [-]"""
    n, spc = trip.shape
    a = (mean - mean.mean()).ravel()
    b = (trip - trip.mean()).ravel()
    score = np.fft.irfft(np.fft.rfft(b) * np.conj(np.fft.rfft(a)), a.size)  # score[s] = sum_i a[i] b[i + s]
    s = int(np.argmax(score))
    lo, mid, hi = score[s - 1], score[s], score[(s + 1) % score.size]
    den = lo - 2 * mid + hi
    frac = 0.5 * (lo - hi) / den if den < 0 else 0.0
    return (s + frac) / spc, float(mid / math.sqrt(np.sum(a * a) * np.sum(b * b)))


def _threshold(lam, dof, alpha):
    """Threshold of the largest statistic over the links seen for a false alarm ``alpha``: each link's statistic an
    F(1, dof) made noncentral by the healthy step's own residual (``lam``)."""
    lam = np.maximum(np.asarray(lam, dtype=float), 1e-12)

    big = lam > 1e3  # where the noncentral F's cdf fails: the statistic is (sqrt(lam) + a unit normal)^2 there

    def over(t):
        log = np.sum(scipy.stats.ncf.logcdf(t, 1, dof, lam[~big]))
        root, shift = math.sqrt(t), np.sqrt(lam[big])
        log += np.sum(
            np.log(np.maximum(scipy.stats.norm.cdf(root - shift) - scipy.stats.norm.cdf(-root - shift), 1e-300))
        )
        return -math.expm1(float(log)) - alpha

    hi = 10.0
    while over(hi) > 0:
        hi *= 2.0
    return float(optimize.brentq(over, 1e-6, hi, xtol=1e-6))
