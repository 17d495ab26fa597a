"""The parts check of :func:`vibkit.diagnose.pitch.estimate_pitch`: does the stated sigma cover the record's own
spread?

A frequency's sigma (the Cramer-Rao bound of the spectral fit, the end-phase noise of the mean-phase
estimate) says how well the record pins down *its* mean frequency; it says nothing of how the source's
frequency moves.  A gait's cadence drifts 2.69-2.75 Hz between 5-minute windows while its mean-phase
sigma over 20 minutes is 0.0004 Hz: another recording of the same source lands a hundred sigmas away.
:func:`check_parts` therefore splits the record into ``K`` parts (4-8, each long enough for the estimator
that the record used), estimates each with that estimator, and compares the parts' scatter with their
own sigmas (the Birge ratio, chi^2 per degree of freedom):

* when the scatter exceeds what the sigmas allow (the chi^2 beyond its :data:`PARTS_P_WIDEN` quantile),
  the sigma is widened to the observed scatter of the mean, ``sqrt(s^2 / K)`` (``s`` the parts' standard
  deviation), or, from eight parts, that of the ``K / 2`` means of neighbouring pairs when it is larger
  (a wander slower than one part leaves neighbours alike), and a warning says so;
* the parts' scatter beyond their sigmas, relative to the frequency, is the source's measured wander;
  :func:`vibkit.diagnose.decision.decide` gives no verdict on a record that wanders more than a chain's
  speed can (:data:`vibkit.diagnose.decision.MAX_PART_WANDER`).

A record too short for :data:`MIN_PARTS` parts is not checked (the result says so in its notes).

**A chain's own once-per-loop pattern is not a wander.**  A worn link (or a damaged roller) changes the
signal's shape each time it passes, once a loop, and a tracked or fitted frequency over a part moves with
it: on the shipped scene with one link 1 mm long, eight parts of a tensioner recording read 3.744-3.756 Hz
(0.12 %, "inconclusive") while the sprocket turned at 3.7485-3.7512 Hz.  Given the chain's number of links,
:func:`check_parts` therefore cuts every burst that covers two loops or more into parts that start at the
same places of each loop (:func:`_loop_split`, ``m`` parts per loop), and compares each part with the parts
at the same place of the other loops (a one-way analysis of variance: the places' means are the pattern, the
scatter around them is the wander).  The sigma is the plain check's, from the parts in time order, as
above: the pattern does move the record's mean frequency (by the phase it has gathered where the record
ends inside a loop), and a sigma from loop-aligned parts covered the sprocket's frequency in only 75-90 %
of healthy-chain records at three sigmas, against 95-100 % (``benchmarks/bench_worn_pitch.py``).
The same record's parts then scatter 0.8 times what their sigmas allow around their places' means: no wander,
and the verdict is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..signal.estimate import harmonic_ls
from ..signal.meanfreq import mean_link_pass_frequency
from .pitch_steps import TRACK_HARMONICS

#: fewest parts the check runs on (three degrees of freedom for the scatter)
MIN_PARTS = 4
#: most parts: more, shorter parts add degrees of freedom but each estimate gets noisier, and a slow drift
#: shows as well in eight parts as in more
MAX_PARTS = 8
#: shortest part for the spectral (harmonic least squares) estimator, in periods of the fundamental: a
#: part's bin (f / periods) stays a small fraction of the frequency and the seeded fit converges
PART_PERIODS_SPECTRAL = 30
#: shortest part for the mean-phase estimator, in periods: what a burst needs to be tracked at all
#: (:data:`vibkit.diagnose.pitch_steps.MIN_TRACK_PERIODS`)
PART_PERIODS_MEAN_PHASE = 40
#: the parts scatter more than their sigmas allow when their chi^2 exceeds its upper quantile at this
#: probability: a steady record's sigma is widened by chance once in a thousand records
PARTS_P_WIDEN = 1e-3
#: most parts per loop in the loop-aligned check (a loop of 159 links at the mean-phase estimator's 40
#: periods gives 3)
MAX_LOOP_PARTS = 8


@dataclass(frozen=True)
class PartsCheck:
    """What :func:`check_parts` found (all SI).

    ``checked`` is False when the record is too short for :data:`MIN_PARTS` parts (``reason`` says so);
    ``frequencies_hz`` and ``sigmas_hz`` are the parts' estimates, ``part_s`` their length, ``birge`` the
    chi^2 per degree of freedom around their weighted mean, ``limit`` its :data:`PARTS_P_WIDEN` quantile,
    ``widened`` whether the sigma was widened (from ``sigma_before_hz`` to ``sigma_hz``), and ``wander``
    the parts' standard deviation beyond their own sigmas over the frequency (relative, 0 when within).
    With the chain's links (``n_links``), ``wander`` is measured around the places' means of loop-aligned parts
    instead, whose Birge ratio and limit are ``place_birge`` and ``place_limit`` (the module notes).
    """

    checked: bool
    reason: str
    frequencies_hz: tuple = ()
    sigmas_hz: tuple = ()
    part_s: float = float("nan")
    birge: float = float("nan")
    limit: float = float("nan")
    widened: bool = False
    sigma_before_hz: float = float("nan")
    sigma_hz: float = float("nan")
    wander: float = 0.0
    warnings: list = field(default_factory=list)
    n_links: int | None = None
    place_birge: float = float("nan")
    place_limit: float = float("nan")

    @property
    def n_parts(self) -> int:
        return len(self.frequencies_hz)

    def as_dict(self) -> dict:
        """JSON-ready (keys carry units; the wander in per cent)."""
        d = {"checked": self.checked, "reason": self.reason}
        if self.checked:
            d.update(
                parts=self.n_parts,
                part_s=self.part_s,
                frequencies_hz=list(self.frequencies_hz),
                sigmas_hz=list(self.sigmas_hz),
                birge_ratio=self.birge,
                birge_limit=self.limit,
                widened=self.widened,
                sigma_before_hz=self.sigma_before_hz,
                sigma_hz=self.sigma_hz,
                wander_percent=100.0 * self.wander,
            )
            if self.n_links:
                d.update(
                    aligned_to_loops_of_links=self.n_links,
                    birge_ratio_around_places=self.place_birge,
                    birge_limit_around_places=self.place_limit,
                )
        return d


def _part_estimate(x, fs, be, f0):
    """``(frequency, sigma)`` of one part with the estimator its burst used, seeded at the record's ``f0``;
    None when the part cannot be estimated."""
    amps = [h.amplitude for h in be.spectral.harmonics]
    try:
        if be.method == "mean-phase":
            r = mean_link_pass_frequency(x, fs, f0=f0, amplitudes=amps, n_harmonics=min(TRACK_HARMONICS, len(amps)))
            f, s = r.frequency_hz, r.sigma_hz
        else:
            k = max(1, min(len(amps), int(0.45 * fs // f0)))
            r = harmonic_ls(x, fs, f_guess=f0, n_harmonics=k)
            f, s = r.frequency_hz, r.sigma_hz
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not (math.isfinite(f) and math.isfinite(s) and s > 0 and abs(f / f0 - 1) < 0.5):
        return None
    return float(f), float(s * be.sigma_factor)  # a long record's decimated parts: their burst's factor


def _split(ests, f0):
    """The parts: ``[(x, fs, burst estimate)]`` and their length [s]; every burst cut into equal parts of one
    length (at least the estimator's shortest part, at most :data:`MAX_PARTS` over the record)."""
    periods = PART_PERIODS_MEAN_PHASE if any(be.method == "mean-phase" for be in ests) else PART_PERIODS_SPECTRAL
    total = sum(be.burst.x.size / be.burst.fs for be in ests)
    part_s = max(periods / f0, total / MAX_PARTS)
    parts = []
    for be in ests:
        b = be.burst
        k = int((b.x.size / b.fs) // part_s)
        if k < 1:
            continue
        m = b.x.size // k
        parts += [(b.x[i * m : (i + 1) * m], b.fs, be) for i in range(k)]
    if len(parts) < MIN_PARTS and len(ests) >= MIN_PARTS:
        # many short bursts (a record of 2 s intervals): each burst is one part, estimated whole
        parts = [(be.burst.x, be.burst.fs, be) for be in ests]
        part_s = float(np.median([be.burst.x.size / be.burst.fs for be in ests]))
    return parts, part_s, periods


def _loop_split(ests, f0, n_links):
    """The loop-aligned parts (module notes): ``([(x, fs, burst estimate, (burst, place))], part length [s],
    parts per loop, periods)``, every burst covering two loops or more cut into whole loops of ``m`` equal
    parts from its start; None when no burst covers two loops or a loop is shorter than one part may be."""
    periods = PART_PERIODS_MEAN_PHASE if any(be.method == "mean-phase" for be in ests) else PART_PERIODS_SPECTRAL
    m = min(MAX_LOOP_PARTS, int(n_links) // periods)
    if m < 1:
        return None
    loop_s = n_links / f0
    parts = []
    for k, be in enumerate(ests):
        b = be.burst
        loops = int((b.x.size / b.fs) // loop_s)
        n = int(loop_s / m * b.fs)
        if loops < 2 or n < 16:
            continue
        parts += [(b.x[j * n : (j + 1) * n], b.fs, be, (k, j % m)) for j in range(loops * m)]
    return (parts, loop_s / m, m, periods) if parts else None


def _around_places(est):
    """The loop-aligned parts' scatter around their places' means: ``(chi^2, degrees of freedom, scatter^2)``,
    every place (burst, place in the loop) with two parts or more counted."""
    chi2 = ss = 0.0
    dof = 0
    for key in sorted({e[2] for e in est}):
        f = np.array([e[0] for e in est if e[2] == key])
        s = np.array([e[1] for e in est if e[2] == key])
        if f.size < 2:
            continue
        w = 1.0 / s**2
        mu = float(np.sum(w * f) / np.sum(w))
        chi2 += float(np.sum(w * (f - mu) ** 2))
        ss += float(np.sum((f - f.mean()) ** 2))
        dof += f.size - 1
    return chi2, dof, ss / dof if dof else math.nan


def _around_loop_places(pc, split, f0, n_links):
    """The plain check ``pc`` with its wander measured around the places' means of loop-aligned parts (module
    notes); ``pc`` with a reason's note where those give too few degrees of freedom."""
    import scipy.stats

    parts, part_s, m, _periods = split
    est = [(_part_estimate(x, fs, be, f0), key) for x, fs, be, key in parts]
    est = [(e[0], e[1], key) for e, key in est if e is not None]
    chi2, dof, scatter2 = _around_places(est)
    if dof < MIN_PARTS - 1:
        loops = 1 + math.ceil((MIN_PARTS - 1) / m)
        why = (
            f"; {dof} degrees of freedom at the same places of loops of {n_links} links: too few to tell a wander "
            f"from the loop's own pattern (record {loops} loops)"
        )
        return replace(pc, reason=pc.reason + why, n_links=n_links)
    s = np.array([e[1] for e in est])
    birge = chi2 / dof
    limit = float(scipy.stats.chi2.isf(PARTS_P_WIDEN, dof) / dof)
    wander = math.sqrt(max(scatter2 - float(np.mean(s**2)), 0.0)) / f0 if birge > limit else 0.0
    where = f"{len(est)} parts of {part_s:.3g} s at {m} places of loops of {n_links} links"
    warnings = [
        w.replace(
            f"(the source's frequency wanders {100 * pc.wander:.2g} %)",
            f"({where} scatter {math.sqrt(birge):.1f} x what their sigmas allow around their places' means: "
            + (
                f"the source's frequency wanders {100 * wander:.2g} %; the rest"
                if wander > 0
                else "no wander; the scatter"
            )
            + " is the chain's own pattern, which repeats every loop)",
        )
        for w in pc.warnings
    ]
    why = f"; {where}: Birge ratio {birge:.3g} around the places' means (limit {limit:.3g})"
    return replace(
        pc,
        reason=pc.reason + why,
        wander=wander,
        warnings=warnings,
        n_links=n_links,
        place_birge=birge,
        place_limit=limit,
    )


def _scatter(f, s, sigma):
    """Parts in time order: ``(Birge ratio, its limit, sigma)`` with the sigma widened to the parts' scatter of
    the mean when the Birge ratio passes its limit (the module notes)."""
    import scipy.stats

    k = f.size
    w = 1.0 / s**2
    fbar = float(np.sum(w * f) / np.sum(w))
    birge = float(np.sum(w * (f - fbar) ** 2) / (k - 1))
    limit = float(scipy.stats.chi2.isf(PARTS_P_WIDEN, k - 1) / (k - 1))
    var_mean = float(np.var(f, ddof=1)) / k
    if k >= 2 * MIN_PARTS:
        # neighbouring parts paired: a wander slower than one part leaves neighbours alike, and the scatter of
        # the mean over the parts alone would understate it (batch means at two lengths, the larger kept)
        h = k // 2
        pairs = (f[: 2 * h : 2] + f[1 : 2 * h : 2]) / 2
        var_mean = max(var_mean, float(np.var(pairs, ddof=1)) / h)
    new = max(sigma, math.sqrt(var_mean)) if birge > limit else sigma
    return birge, limit, new


def check_parts(ests, comb, n_links=None):
    """The parts check (module notes): ``(PartsCheck, sigma)`` with ``sigma`` the combined sigma, widened to
    the parts' scatter of the mean when they disagree beyond their own sigmas.  With the chain's number of links
    ``n_links`` and a burst over two loops, the wander is measured around the places' means of loop-aligned parts
    (:func:`_around_loop_places`)."""
    f0, sigma = comb.f0, comb.sigma
    parts, part_s, periods = _split(ests, f0)
    if len(parts) < MIN_PARTS:
        why = (
            f"record too short for the parts check ({MIN_PARTS} parts of {periods} periods, "
            f"{MIN_PARTS * periods / f0:.3g} s, needed): the sigma is not checked against the record's spread"
        )
        return PartsCheck(False, why, sigma_before_hz=sigma, sigma_hz=sigma), sigma
    est = [_part_estimate(x, fs, be, f0) for x, fs, be in parts]
    est = [e for e in est if e is not None]
    if len(est) < MIN_PARTS:
        why = f"only {len(est)} of {len(parts)} parts could be estimated: the sigma is not checked"
        return PartsCheck(False, why, sigma_before_hz=sigma, sigma_hz=sigma), sigma
    f = np.array([e[0] for e in est])
    s = np.array([e[1] for e in est])
    k = f.size
    birge, limit, new = _scatter(f, s, sigma)
    widened = new > sigma
    # within what the parts' own sigmas allow: no measured wander
    wander = math.sqrt(max(float(np.var(f, ddof=1)) - float(np.mean(s**2)), 0.0)) / f0 if birge > limit else 0.0
    warnings = []
    if widened:
        warnings.append(
            f"the frequency's sigma widened from {sigma:.2g} to {new:.2g} Hz: {k} parts of {part_s:.3g} s give "
            f"{f.min():.5g}-{f.max():.5g} Hz, a scatter {math.sqrt(birge):.1f} x what their sigmas allow "
            f"(the source's frequency wanders {100 * wander:.2g} %)"
        )
    why = f"{k} parts of {part_s:.3g} s: Birge ratio {birge:.3g} (chi^2 per degree of freedom; limit {limit:.3g}); " + (
        f"sigma widened to the parts' scatter of the mean ({new:.2g} Hz)" if widened else "sigma kept"
    )
    pc = PartsCheck(True, why, tuple(f), tuple(s), part_s, birge, limit, widened, sigma, new, wander, warnings)
    split = _loop_split(ests, f0, n_links) if n_links else None
    if split is not None:
        pc = _around_loop_places(pc, split, f0, int(n_links))
    return pc, new
