"""Does a forward run's physics still change with the tolerance? A verdict, not a guess.

A result counts only when it no longer changes with the tolerance. :func:`checked_forward` runs the
scene at its tolerance and again at a tolerance 100 times tighter, and compares what a user reads
from the run (:func:`summary`): the episodes of tooth contact and of back-flank contact, the time of
the last contact, the sprocket speed ripple and the delta ripple over the second half of the run,
the peak link tension (when the scene asks for tensions) and the dominant frequencies of delta and
of the sprocket speed (a touch of a tooth below what the run resolves, :func:`contact_floor`, is not
contact). When the two agree the run is *converged* at the scene's tolerance. When they
do not, the check goes on tightening by 100 within its budget (down to ``[solver] check_min_rtol``,
default 1e-12, and the wall-time budget of each run) and reports the loosest tolerance whose run
agrees with the next tighter one: the run is *not converged* at the scene's tolerance, and that
tolerance is the one to use. When no two runs agree, the history itself depends on the rounding:
the regime is *sensitive* (chaotic; an undamped stiff chain in its backlash is one), no converged
contact history exists, and the verdict lists the quantities that still agree over every run (the
means and the spectra's peaks), the only ones worth reading.

The verdict lands in the result's attributes: ``convergence`` (JSON) and ``converged`` (1 or 0).
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from ..model.escalator import EscalatorModel
from ..model.schema import ContactOptions, SolverSection
from .forward import default_rtol, forward_dynamics

__all__ = ["checked_forward", "contact_floor", "summary", "compare", "verdict", "CHECK_FACTOR", "DEFAULT_MIN_RTOL"]

CHECK_FACTOR = 100.0  # each check run is this much tighter than the one before
#: the tightest tolerance the search tries, unless [solver] check_min_rtol (the schema's default)
DEFAULT_MIN_RTOL = SolverSection.check_min_rtol
# outputs the comparison needs, computed at the output times whatever the scene asks for
NEEDED = ("flank_force", "sprocket_speed", "delta")


def _episodes(on):
    return int(on[0]) + int(np.count_nonzero(np.diff(on.astype(np.int8)) == 1)) if on.size else 0


def _peak_frequency(x, dt, margin=False):
    """Dominant frequency of x (mean and linear drift removed, above 3 / record length; Hann window, zero-padded 16 times,
    parabolic peak) [Hz]; with ``margin``, its peak over the highest elsewhere instead."""
    x = np.asarray(x, dtype=float)
    if x.size < 8 or not np.ptp(x) > 0:
        return None
    i = np.arange(x.size)
    x = x - np.polyval(np.polyfit(i, x, 1), i)  # the mean and a drift are not a frequency
    n = 16 * x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    lo = 16 * 3  # from three bins of the record up (below, the window's own lobe)
    k = int(np.argmax(spec[lo:])) + lo
    if margin:
        # the peak over the highest elsewhere (two record bins away): near 1, two peaks take turns being the highest
        rest = np.concatenate([spec[lo : max(lo, k - 32)], spec[k + 33 :]])
        return float(spec[k] / rest.max()) if rest.size and rest.max() > 0 else None
    if 1 <= k < spec.size - 1 and spec[k - 1] > 0 and spec[k + 1] > 0:
        a, b, c = np.log(spec[k - 1 : k + 2])
        den = a - 2 * b + c
        k = k + (min(0.5, max(-0.5, 0.5 * (a - c) / den)) if den != 0 else 0.0)
    return float(k / (n * dt))


def contact_floor(effects, rtol):
    """The smallest flank force a run at ``rtol`` resolves: that of an indentation of ten times the
    tolerance (the positions' tolerance is ``rtol`` metres), ``k (10 rtol)^e``; 0 without contact. [N]

    A touch below it is a graze the run does not resolve: it does not make a contact history. (On the
    E12 fleet profile at 1e-7 a change of step sequence alone once put a roller on a tooth by 0.57 um,
    4e-4 N, after three touches of 14-46 um, 0.05-0.3 N, that the runs at 1e-9 and 1e-11 agree on.)
    """
    contact = effects.get("contact") if hasattr(effects, "get") else None
    if contact is None:
        return 0.0
    if isinstance(contact, dict):
        contact = ContactOptions.from_mapping(contact)
    return float(contact.stiffness * (10.0 * rtol) ** contact.exponent)


def summary(ds, force_floor=0.0):
    """What a user reads from a forward run, from a dataset with drive_flank_force,
    back_flank_force, sprocket_speed and delta (and link_tension if the scene asks for it).

    Episodes are runs of output samples with a force above ``force_floor`` [N] on any flank (on the
    back flanks; :func:`contact_floor`), the last contact the last such sample [s]; ripples and frequencies are taken over the second half of the
    run (after the start-up): sprocket speed ripple (max - min) / |mean| [%], delta ripple
    max - min [m], their dominant frequencies [Hz], and the means of both.
    """
    t = ds.time.values
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    drive = np.abs(ds.drive_flank_force.values) > force_floor
    back = np.abs(ds.back_flank_force.values) > force_floor
    on = drive | back
    half = t >= 0.5 * t[-1]
    w = ds.sprocket_speed.values[half]
    d = ds.delta.values[half]
    out = {
        "contact_episodes": _episodes(on),
        "back_flank_episodes": _episodes(back),
        "last_contact_s": float(t[np.flatnonzero(on)[-1]]) if on.any() else None,
        "sprocket_ripple_percent": float(100.0 * np.ptp(w) / abs(w.mean())) if abs(w.mean()) > 0 else 0.0,
        "delta_ripple_m": float(np.ptp(d)),
        "sprocket_speed_frequency_hz": _peak_frequency(w, dt),
        "sprocket_speed_peak_margin": _peak_frequency(w, dt, margin=True),
        "delta_frequency_hz": _peak_frequency(d, dt),
        "mean_sprocket_speed_rad_s": float(w.mean()),
        "mean_delta_m": float(d.mean()),
    }
    if "link_tension" in ds:
        out["peak_tension_n"] = float(np.abs(ds.link_tension.values).max())
    return out


# what is compared, and how close counts as the same (the looser run's rtol enters the floors:
# a ripple below ten times the tolerance is below what the run resolves)
HISTORY = (
    "contact_episodes",
    "back_flank_episodes",
    "last_contact_s",
    "sprocket_ripple_percent",
    "delta_ripple_m",
    "peak_tension_n",
    "sprocket_speed_frequency_hz",
    "delta_frequency_hz",
)
ROBUST = ("mean_sprocket_speed_rad_s", "mean_delta_m", "sprocket_speed_frequency_hz", "delta_frequency_hz")


def _close(name, a, b, rtol, dt, duration):
    if a is None or b is None:
        return a is None and b is None
    if name.endswith("episodes"):
        return a == b
    if name == "last_contact_s":
        return abs(a - b) <= 2.0 * dt + 1e-9
    if name == "sprocket_ripple_percent":
        return abs(a - b) <= 0.25 * max(abs(a), abs(b)) + 100.0 * 10.0 * rtol
    if name == "delta_ripple_m":
        return abs(a - b) <= 0.05 * max(abs(a), abs(b)) + 1e-8
    if name == "peak_tension_n":
        return abs(a - b) <= 0.01 * max(abs(a), abs(b)) + 1.0
    if name.endswith("frequency_hz"):
        # within two bins of the spectrum of the second half
        return abs(a - b) <= 2.0 / (0.5 * duration) + 0.01 * max(abs(a), abs(b))
    if name == "mean_sprocket_speed_rad_s":
        return abs(a - b) <= 1e-3 * max(abs(a), abs(b)) + 1e-9
    if name == "mean_delta_m":
        return abs(a - b) <= 1e-3 * max(abs(a), abs(b)) + 1e-7
    raise KeyError(name)


#: a dominant frequency is compared only where its peak stands this many times above the next one
PEAK_MARGIN = 1.5


def compare(s1, s2, rtol, dt, duration, names=HISTORY):
    """Quantities of ``names`` on which two summaries differ: {name: [first, second]}.

    The dominant frequency of a ripple below what the runs resolve (a sprocket turning steadily, to
    ten times the tolerance) is the frequency of rounding: it is not compared, nor is that of a sprocket ripple with
    two peaks within :data:`PEAK_MARGIN` of each other in either run.
    """
    skip = set()
    ripple = [s.get("sprocket_ripple_percent") or 0.0 for s in (s1, s2)]
    if max(ripple) <= 100.0 * 10.0 * rtol:
        skip.add("sprocket_speed_frequency_hz")
    # two peaks of the sprocket's ripple within 3.5 dB of each other: which is the higher is no history of the run
    # (a stranger's scene: 4.79 and 0.297 Hz in turn, the ripple, contact history and delta agreeing to 4 digits)
    if min((s.get("sprocket_speed_peak_margin") or math.inf) for s in (s1, s2)) < PEAK_MARGIN:
        skip.add("sprocket_speed_frequency_hz")
    if max(s.get("delta_ripple_m") or 0.0 for s in (s1, s2)) <= 1e-8:
        skip.add("delta_frequency_hz")
    return {
        k: [s1.get(k), s2.get(k)]
        for k in names
        if (k in s1 or k in s2) and k not in skip and not _close(k, s1.get(k), s2.get(k), rtol, dt, duration)
    }


def verdict(runs, dt, duration, min_rtol):
    """The verdict from runs [(rtol, summary, cpu_s)], loosest first (see the module's doc)."""
    rt0 = runs[0][0]
    out = {
        "rtol": rt0,
        "min_rtol": min_rtol,
        "factor": CHECK_FACTOR,
        "runs": [{"rtol": r, "cpu_s": round(c, 3), **s} for r, s, c in runs],
    }
    first = compare(runs[0][1], runs[1][1], rt0, dt, duration) if len(runs) > 1 else {}
    out["differences"] = first
    agree_at = None
    for (ra, sa, _), (_rb, sb, _) in zip(runs, runs[1:]):
        if not compare(sa, sb, ra, dt, duration):
            agree_at = ra
            break
    out["converged"] = bool(len(runs) > 1 and not first)
    out["agrees_at_rtol"] = agree_at
    out["sensitive"] = bool(agree_at is None and len(runs) > 2)
    if out["converged"]:
        out["message"] = (
            f"converged: the run at rtol {rt0:g} and one at {rt0 / CHECK_FACTOR:g} agree on the contact "
            "history, ripples, peak tension and dominant frequencies"
        )
    elif agree_at is not None:
        out["message"] = (
            f"not converged at rtol {rt0:g} (differs in {', '.join(first)}); the runs agree from rtol "
            f"{agree_at:g}: set [solver] rtol = {agree_at:g}"
        )
    elif out["sensitive"]:
        robust = [
            k
            for k in ROBUST
            if all(not compare(sa, sb, ra, dt, duration, (k,)) for (ra, sa, _), (_, sb, _) in zip(runs, runs[1:]))
        ]
        out["robust"] = robust
        out["message"] = (
            f"sensitive: no two runs from rtol {rt0:g} to {runs[-1][0]:g} agree on the contact history "
            "(a chaotic regime: the history depends on rounding, no converged one exists); still robust: "
            + (", ".join(robust) if robust else "nothing compared")
        )
    else:
        out["message"] = (
            f"not converged at rtol {rt0:g} (differs in {', '.join(first)}); the budget (rtol down to "
            f"{min_rtol:g}) ran out before two runs agreed"
        )
    return out


def checked_forward(model, *, duration=None, progress=True, min_rtol=None, parallel=True):
    """Forward run of ``model.scene`` at its tolerance, with the convergence verdict in its attrs.

    The search's budget: runs tighter by :data:`CHECK_FACTOR` each, down to ``min_rtol`` (default
    the scene's ``[solver] check_min_rtol``, else 1e-12), each under the scene's wall-time budget.
    With ``parallel`` and more than one core, the run and the first tighter one run at once (two
    threads; the same numbers as one after the other).
    """
    scene = model.scene
    solver = scene.solver
    outputs = tuple(scene.outputs["variables"])
    rtol = solver.rtol or default_rtol(scene.effects)
    atol = solver.atol_for(rtol)
    min_rtol = min_rtol or solver.check_min_rtol
    want = tuple(dict.fromkeys(outputs + NEEDED))
    duration = duration or scene.run.duration
    dt = scene.run.output_step

    def run(r, outs, mdl=None, show=False):
        """One run; the check's runs each on a fresh model, so that every run is the same whether it
        runs alone, after another or beside one (a model keeps its last closure as a guess)."""
        c0 = time.thread_time()  # this thread's CPU time: the first two runs may run at once
        mdl = EscalatorModel(scene) if mdl is None else mdl
        ds = forward_dynamics(mdl, duration=duration, progress=show, rtol=r, atol=atol * r / rtol, outputs=outs)
        return ds, time.thread_time() - c0

    compared = tuple(k for k in want if k in NEEDED or k == "link_tension")
    first = float(f"{rtol / CHECK_FACTOR:.12g}")
    if first >= min_rtol * (1 - 1e-9) and parallel and (os.cpu_count() or 1) > 1:
        # the run and the first tighter one at once, each on its own model (the chain's Python-side
        # scratch arrays are not shared); the compiled integrator releases the GIL
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(2) as pool:
            fut = pool.submit(run, first, compared, EscalatorModel(scene))
            ds, cpu = run(rtol, want, model, show=progress)
            tight, cpu_t = fut.result()
        pre = [(first, tight, cpu_t)]
    else:
        ds, cpu = run(rtol, want, model, show=progress)
        pre = []

    def floor(r):
        return contact_floor(scene.effects, r)

    runs = [(rtol, summary(ds, floor(rtol)), cpu)]
    r = rtol
    while r / CHECK_FACTOR >= min_rtol * (1 - 1e-9):
        r = float(f"{r / CHECK_FACTOR:.12g}")
        if pre:
            _, tight, cpu_r = pre.pop()
        else:
            tight, cpu_r = run(r, compared)
        runs.append((r, summary(tight, floor(r)), cpu_r))
        if len(runs) == 2 and not compare(runs[0][1], runs[1][1], rtol, dt, duration):
            break  # converged at the scene's tolerance
        if len(runs) > 2 and not compare(runs[-2][1], runs[-1][1], runs[-2][0], dt, duration):
            break  # found the tolerance from which the runs agree
    if len(runs) == 1:
        # no tighter run fits the budget (a stiff contact's default tolerance is near check_min_rtol): a looser
        # run tells whether the result still changes with the tolerance
        r = float(f"{rtol * CHECK_FACTOR:.12g}")
        loose, cpu_r = run(r, compared)
        runs.insert(0, (r, summary(loose, floor(r)), cpu_r))
        v = verdict(runs, dt, duration, min_rtol)
        v["rtol"] = rtol
        v["message"] = (
            f"converged: the run at rtol {rtol:g} and a looser one at {r:g} agree on the contact history, "
            f"ripples, peak tension and dominant frequencies (no tighter run fits the check's budget, "
            f"check_min_rtol = {min_rtol:g})"
            if v["converged"]
            else f"not converged at rtol {rtol:g}: a looser run at {r:g} differs in {', '.join(v['differences'])}, "
            f"and no tighter run fits the check's budget (check_min_rtol = {min_rtol:g}): lower [solver] "
            "check_min_rtol to test tighter tolerances"
        )
    elif len(runs) == 2 and compare(runs[0][1], runs[1][1], rtol, dt, duration):
        # the budget allowed one tighter run only, and it differs: a looser run tells a history that
        # needs a tighter tolerance from one that no tolerance fixes (three runs, none agreeing)
        r = float(f"{rtol * CHECK_FACTOR:.12g}")
        loose, cpu_r = run(r, compared)
        runs.insert(0, (r, summary(loose, floor(r)), cpu_r))
        v = verdict(runs, dt, duration, min_rtol)
        v["rtol"] = rtol
        v["differences"] = compare(runs[1][1], runs[2][1], rtol, dt, duration)
        v["converged"] = False
        if v["agrees_at_rtol"] is not None:  # the looser pair agreeing says nothing about rtol
            v["agrees_at_rtol"] = None
            v["message"] = (
                f"not converged at rtol {rtol:g} (differs in {', '.join(v['differences'])}); the budget "
                f"(rtol down to {min_rtol:g}) ran out before two runs agreed"
            )
    else:
        v = verdict(runs, dt, duration, min_rtol)
    drop = [
        name
        for name in ("drive_flank_force", "back_flank_force", "sprocket_speed", "delta")
        if name in ds and name not in outputs and not (name.endswith("flank_force") and "flank_force" in outputs)
    ]
    ds = ds.drop_vars(drop)
    ds.attrs["convergence"] = json.dumps(v, default=float)
    ds.attrs["converged"] = int(v["converged"])
    return ds
