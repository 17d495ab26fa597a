"""The decision: is an estimate the link pass of *this* chain, and does it support a verdict?

One function, :func:`decide`, shared by every consumer of a link-pass estimate (``vibkit spectrum``,
``pitch``, ``report``, ``compare``, the fleet).  It returns a :class:`Decision` whose ``status`` is

``"ok"``
    a link-pass family was detected, the estimate belongs to it, lies in the search band, and the
    pitch it implies is physically plausible; with a nominal pitch the elongation is resolved well
    enough for a verdict (exit 0);
``"no link-pass found"``
    no family, or the estimate is not the detected family's fundamental (a different frequency than
    the detection's within its resolution), lies outside the search band, or wanders more than a
    chain's speed can (exit 1, no pitch);
``"implausible"``
    a family was found, but the pitch it implies is not this chain's: an elongation outside
    :data:`ELONGATION_WINDOW_PERCENT` of the nominal pitch, or (without a nominal pitch) of every
    standard step-chain pitch in :data:`CATALOGUE_PITCHES_M` (exit 1, no pitch; the reason says
    what the family implies and what to check);
``"inconclusive"``
    the family is there and plausible, but either its elongation is not resolved to a third of the
    first limit, or it is one spectral line without a significant harmonic (a tone that a structural
    mode, a motor or a fan gives as well), or its frequency wanders between parts of the record more
    than a chain's speed can (:data:`MAX_PART_WANDER`: a gait, a cadence): frequency, pitch and
    elongation with their sigmas, verdict ``"inconclusive"`` (exit 3).

Why -1 % to +6 %: a roller chain only lengthens with wear (pins and bushes wear, the pitch grows); a
new chain is made to its nominal length within a few tenths of a per cent (ISO 606 allows 0 to
+0.15 % on a measured length), so -1 % leaves room for the speed's and the estimate's errors and
nothing else.  A worn step chain is replaced at 3 % (vibkit's default limits 1.5 / 2 / 3 %); +6 % is
twice the replacement limit, a chain no maintained escalator runs on, while still covering a chain
that was missed for years.  A reading outside the window is another periodicity, a wrong speed or a
wrong nominal pitch, never a verdict.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .rounding import SPEED_SIGMA_NOT_STATED, fmt_pm

__all__ = [
    "CATALOGUE_PITCHES_M",
    "CATALOGUE_SOURCES",
    "DEFAULT_LIMITS_PERCENT",
    "ELONGATION_WINDOW_PERCENT",
    "EXIT_CODES",
    "MAX_PART_WANDER",
    "MAX_WANDER",
    "STATUS_IMPLAUSIBLE",
    "STATUS_INCONCLUSIVE",
    "STATUS_NOT_FOUND",
    "STATUS_OK",
    "Decision",
    "LinkPassEvidence",
    "decide",
    "elongation_verdict",
    "nearest_catalogue",
]

STATUS_OK = "ok"
STATUS_NOT_FOUND = "no link-pass found"
STATUS_IMPLAUSIBLE = "implausible"
STATUS_INCONCLUSIVE = "inconclusive"
#: what an inconclusive reason says where the elongation's sigma holds but is too large for a verdict (the other
#: inconclusive reasons say the estimate itself is not to be trusted)
SIGMA_TOO_LARGE = "more than a third of the first limit"
#: exit status of the CLI for each status (2 stays the usage error)
EXIT_CODES = {STATUS_OK: 0, STATUS_NOT_FOUND: 1, STATUS_IMPLAUSIBLE: 1, STATUS_INCONCLUSIVE: 3}
#: elongation limits [%]: watch, plan replacement, replace
DEFAULT_LIMITS_PERCENT = (1.5, 2.0, 3.0)
#: physically possible elongation of a running chain against its nominal pitch [%] (module notes)
ELONGATION_WINDOW_PERCENT = (-1.0, 6.0)
#: standard escalator step-chain pitches [m]: steps every ~406 mm carried on every 6th, 5th or 4th
#: link (Tsubaki, The Complete Guide to Chain, 2.2.1 "Step (Escalator) Chain", table 2.5: 67.7,
#: 81.3, 101.6 mm), 400 mm / 3 (the reference escalator of the study), and the
#: Otis T135.4 step chain (135.46 mm, supplier data sheets)
CATALOGUE_PITCHES_M = (0.0677, 0.0813, 0.1016, 0.4 / 3.0, 0.13546)
CATALOGUE_SOURCES = (
    "Tsubaki, The Complete Guide to Chain, 2.2.1 Step (Escalator) Chain, table 2.5 (67.7, 81.3, 101.6 mm)",
    "400 mm step / 3 links (133.33 mm), the study's reference escalator",
    "Otis T135.4 step chain, 135.46 mm (supplier data sheets)",
)
#: largest relative difference between the spectral and the mean-phase estimate of one record: an
#: escalator's speed wanders by a few per cent with load, a chirp, a gait or a ride by more
MAX_WANDER = 0.025
#: largest wander of the link-pass frequency between parts of one record (the parts' standard deviation
#: beyond their own sigmas, relative to the frequency) that still allows a verdict.  The speed given is one
#: number, and a verdict needs it to about 0.1 % (the elongation resolved to 0.5 %, a third of the 1.5 %
#: watch limit, with the frequency's part of the error as small): a frequency that moves by more within
#: the record cannot be matched to one speed that well.  A chain under its speed controller holds it:
#: the reference model's P controller runs 0.2 % below its set speed empty (3.742 for 3.75 Hz) and a
#: steady load shifts that offset, not the wander within a record; EN 115-1 bounds the mean speed
#: (+-5 % of nominal at no load), not a record's wander.  Steady chain signals scatter between parts
#: by their noise (0.00-0.03 % excess at -5 dB per sample); a gait's cadence wandering +-1 % over minutes
#: shows 0.2-0.5 % (benchmarks/bench_coverage.py).  The +-2 % speed wander of the stress signals of the
#: estimators (tests/support/chain.py ``wandering``) shows 0.3-1.5 %: more than a chain under speed
#: control does within one record, so those keep their pitch without a verdict
MAX_PART_WANDER = 0.001
#: spectral and mean-phase estimates of one record further apart than this many combined sigmas: the
#: link-pass frequency is not stationary within the record
DISAGREE_SIGMAS = 5.0
#: the elongation must be resolved to this fraction of the first limit for a verdict: its sigma a third of
#: the first limit puts the watch limit three sigmas from a new chain
EVIDENCE_FRACTION = 1.0 / 3.0
#: the estimate belongs to the detected family when it lies within the detection's bin width (half of it for a
#: record too short to track the phase: a spectral estimate only) plus this many of its own sigmas of the
#: detection's frequency (three sigmas: a 0.3 % chance to refuse a true family)
SAME_FAMILY_SIGMAS = 3.0


@dataclass(frozen=True)
class Decision:
    """What vibkit may say about one estimate (see the module notes).

    Attributes
    ----------
    status : str
        ``"ok"``, ``"no link-pass found"``, ``"implausible"`` or ``"inconclusive"``.
    reason : str
        One or two sentences: why (and, for a refusal, what to check).
    verdict : str or None
        ``"ok"``, ``"watch"``, ``"plan replacement"``, ``"replace"`` or ``"inconclusive"``; None
        without a nominal pitch or when refused.
    implied_pitch_m : float or None
        The pitch the detected family implies at the given speed (also for an implausible one). [m]
    checks : dict
        Each check run: name -> passed (bool).
    """

    status: str
    reason: str
    verdict: str | None = None
    implied_pitch_m: float | None = None
    checks: dict = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        """CLI exit status: 0 ok, 1 no link-pass found or implausible, 3 inconclusive."""
        return EXIT_CODES[self.status]

    @property
    def has_link_pass(self) -> bool:
        """True when a frequency (and pitch) may be reported: ``ok`` or ``inconclusive``."""
        return self.status in (STATUS_OK, STATUS_INCONCLUSIVE)

    @property
    def flagged(self) -> bool:
        """True when a fleet must not use the measurement in a trend (anything but ``ok``)."""
        return self.status != STATUS_OK

    def as_dict(self) -> dict:
        return {
            "status": self.status,
            "reason": self.reason,
            "verdict": self.verdict,
            "implied_pitch_m": self.implied_pitch_m,
            "exit_code": self.exit_code,
            "checks": dict(self.checks),
        }


def elongation_verdict(elongation_percent, limits_percent=DEFAULT_LIMITS_PERCENT) -> str:
    """Verdict for a chain elongation [%] against three increasing limits [%].

    Returns one of ``"ok"`` (below the first), ``"watch"``, ``"plan replacement"``, ``"replace"``
    (at or above the third).  A shortened chain (negative elongation beyond the first limit) is
    ``"check speed"``: chains do not shrink, so the speed or the nominal pitch is wrong.
    """
    lim = check_limits(limits_percent)
    e = float(elongation_percent)
    if e <= -lim[0]:
        return "check speed"
    if e < lim[0]:
        return "ok"
    if e < lim[1]:
        return "watch"
    if e < lim[2]:
        return "plan replacement"
    return "replace"


def check_limits(limits):
    """Three increasing positive percentages, or ValueError."""
    try:
        lim = tuple(float(v) for v in limits)
    except (TypeError, ValueError):
        raise ValueError(f"limits must be three numbers [%], got {limits!r}") from None
    if len(lim) != 3 or not 0 < lim[0] < lim[1] < lim[2]:
        raise ValueError(f"limits must be three increasing positive percentages, got {limits!r}")
    return lim


def nearest_catalogue(pitch_m, catalogue=CATALOGUE_PITCHES_M):
    """``(catalogue pitch, deviation [%])`` of the catalogue pitch nearest (relatively) to ``pitch_m``."""
    c = min(catalogue, key=lambda q: abs(pitch_m / q - 1))
    return c, 100.0 * (pitch_m / c - 1.0)


def _mm(p):
    return f"{1000 * p:.1f} mm"


def _nominal_mm(p):
    """A pitch given (a nominal, a catalogue's) as given: 135.47 mm, 101.6 mm, not rounded to 135.5."""
    return f"{1000 * p:.6g} mm"


@dataclass(frozen=True)
class LinkPassEvidence:
    """What the detection and the estimation found about one record: the input of :func:`decide`.

    Attributes
    ----------
    detected : bool
        The detection test (:func:`vibkit.signal.detect.detect_link_pass`) found a family.
    detection_reason : str
        Its one-line reason (quoted when nothing was found).
    detection_hz, resolution_hz : float
        The family's fundamental as the test found it, and the test's bin width. [Hz]
    fundamental_hz, fundamental_sigma_hz : float
        The estimate and its standard deviation. [Hz]
    band_hz : (float, float), optional
        Search band. [Hz]
    speed_m_s, speed_sigma_m_s : float, optional
        Chain speed (None: frequency only, no pitch, no plausibility) and its sigma (None: not stated; the
        reasons then give the elongation without a sigma, the frequency's part being a lower bound). [m/s]
    nominal_pitch_m : float, optional
        Nominal pitch: plausibility against it, elongation verdict. [m]
    limits_percent : (float, float, float)
        Elongation limits: watch, plan replacement, replace. [%]
    spectral_hz, mean_phase_hz : float, optional
        The two estimates of a record when both exist (steadiness check). [Hz]
    methods_sigmas : float, optional
        Their difference in combined sigmas.  Over :data:`DISAGREE_SIGMAS` and :data:`MAX_PART_WANDER` of the
        frequency: ``inconclusive`` (the frequency moves within the record).
    speed_source : str
        Where the speed came from (named in the reasons).
    significant_orders : sequence of int, optional
        Harmonic orders individually significant in the detection; fewer than two (a lone spectral line,
        which a structural mode, a motor or a fan gives as well) make the result ``inconclusive``.
    part_wander : float, optional
        The frequency's wander between parts of the record (standard deviation beyond the parts' sigmas,
        relative; :func:`vibkit.diagnose.pitch_parts.check_parts`); None when not checked.  Over
        :data:`MAX_WANDER` refused, over :data:`MAX_PART_WANDER` ``inconclusive``.
    part_summary : str
        The parts' frequencies in a few words, quoted in the reason.
    """

    detected: bool
    detection_reason: str = ""
    detection_hz: float = float("nan")
    resolution_hz: float = float("nan")
    fundamental_hz: float = float("nan")
    fundamental_sigma_hz: float = float("nan")
    band_hz: tuple | None = None
    speed_m_s: float | None = None
    speed_sigma_m_s: float | None = 0.0
    nominal_pitch_m: float | None = None
    limits_percent: tuple = DEFAULT_LIMITS_PERCENT
    spectral_hz: float | None = None
    mean_phase_hz: float | None = None
    methods_sigmas: float | None = None
    speed_source: str = "given"
    significant_orders: tuple | None = None
    part_wander: float | None = None
    part_summary: str = ""


def decide(
    evidence: LinkPassEvidence, *, window_percent=ELONGATION_WINDOW_PERCENT, catalogue=CATALOGUE_PITCHES_M
) -> Decision:
    """The decision on one link-pass estimate (module notes).

    The checks run in this order, the first that fails deciding: a family detected, a fundamental
    estimated, the estimate the detected family's, in the band, steady (:func:`_check_family`); the pitch
    it implies plausible (:func:`_check_plausible`); harmonics present (:func:`_check_harmonics`); the
    elongation resolved for a verdict (:func:`_verdict`).

    Parameters
    ----------
    evidence : LinkPassEvidence
        What the detection and the estimation found.
    window_percent : (float, float)
        Physically possible elongation. [%]
    catalogue : tuple of float
        Standard pitches used without a nominal pitch. [m]

    Returns
    -------
    Decision
    """
    ev = evidence
    checks = {}
    refused = _check_family(ev, checks)
    if refused is not None:
        return refused
    f = float(ev.fundamental_hz)
    if ev.speed_m_s is None:
        return Decision(
            STATUS_OK, f"link-pass family at {f:.4g} Hz (no speed: no pitch, plausibility not checked)", checks=checks
        )
    p = float(ev.speed_m_s) / f
    return (
        _check_plausible(ev, p, checks, window_percent, catalogue)
        or _check_harmonics(ev, p, checks)
        or _check_methods_agree(ev, p, checks)
        or _check_parts_wander(ev, p, checks)
        or _verdict(ev, p, checks)
    )


def _check_family(ev, checks):
    """A refusal (``no link-pass found``) unless a family was detected, its fundamental estimated, and the
    estimate is the detected family's (within the resolution and :data:`SAME_FAMILY_SIGMAS`), in the band
    and steady (:data:`MAX_WANDER`); None when every check passes."""
    if not ev.detected:
        checks["detected"] = False
        return Decision(STATUS_NOT_FOUND, ev.detection_reason or "no harmonic family in the band", checks=checks)
    checks["detected"] = True
    f, sf = float(ev.fundamental_hz), float(ev.fundamental_sigma_hz)
    if not (math.isfinite(f) and f > 0):
        checks["estimated"] = False
        return Decision(STATUS_NOT_FOUND, "a family was detected but no fundamental could be estimated", checks=checks)
    sf = sf if math.isfinite(sf) else 0.0
    fd, res = float(ev.detection_hz), float(ev.resolution_hz)
    if math.isfinite(fd) and math.isfinite(res):
        # the detector's frequency is its nearest bin's (half a bin away at most); a whole bin where the record was
        # long enough to track the phase, whose frequency may wander over more than half a bin (a sinusoidal wander
        # puts the spectral peak near its extremes): bench_pitch's +-2 % wander lost 3-9 % of its link passes to
        # half a bin
        slack = res if ev.mean_phase_hz is not None else 0.5 * res
        same = abs(f - fd) <= slack + SAME_FAMILY_SIGMAS * sf
        checks["same family"] = bool(same)
        if not same:
            return Decision(
                STATUS_NOT_FOUND,
                (
                    f"the estimate {f:.4g} Hz is not the fundamental of the detected family ({fd:.4g} Hz, resolution "
                    f"{res:.2g} Hz): the record does not hold one steady family (too short, a transient, a sweep)"
                ),
                checks=checks,
            )
    if ev.band_hz is not None:
        lo, hi = (float(v) for v in ev.band_hz)
        inside = lo <= f <= hi
        checks["in band"] = bool(inside)
        if not inside:
            return Decision(
                STATUS_NOT_FOUND,
                (
                    f"the estimate {f:.4g} Hz lies outside the search band {lo:.4g}-{hi:.4g} Hz: not a link pass "
                    "of this chain at this speed"
                ),
                checks=checks,
            )
    if ev.spectral_hz is not None and ev.mean_phase_hz is not None:
        spectral, mean_phase = float(ev.spectral_hz), float(ev.mean_phase_hz)
        rel = abs(spectral - mean_phase) / f
        steady = rel <= MAX_WANDER
        checks["steady"] = bool(steady)
        if not steady:
            return Decision(
                STATUS_NOT_FOUND,
                (
                    f"the spectral ({spectral:.4g} Hz) and mean-phase ({mean_phase:.4g} Hz) estimates "
                    f"differ by {100 * rel:.2g} %: a chain's speed wanders by a few per cent at most "
                    f"({100 * MAX_WANDER:g} % allowed); this periodicity drifts like a gait, a ride or a sweep"
                ),
                checks=checks,
            )
    if ev.part_wander is not None and ev.part_wander > MAX_WANDER:
        checks["steady"] = False
        return Decision(
            STATUS_NOT_FOUND,
            (
                f"the frequency wanders {100 * ev.part_wander:.2g} % between parts of the record ({ev.part_summary}): "
                f"a chain's speed wanders by a few per cent at most ({100 * MAX_WANDER:g} % allowed); this "
                "periodicity drifts like a gait, a ride or a sweep"
            ),
            checks=checks,
        )
    return None


def _check_plausible(ev, p, checks, window_percent, catalogue):
    """``implausible`` when the pitch ``p`` [m] lies outside the window around the nominal pitch (or, without
    one, around every catalogue pitch); None when plausible."""
    f, v = float(ev.fundamental_hz), float(ev.speed_m_s)
    wlo, whi = (float(x) for x in window_percent)
    # a speed known to 5 % cannot tell a pitch 3 % short from a nominal one: the window widens by two sigmas of the
    # implied pitch (speed and frequency), so that "implausible" is said only where the data exclude the chain
    sf = float(ev.fundamental_sigma_hz) if math.isfinite(float(ev.fundamental_sigma_hz)) else 0.0
    widen = 200.0 * math.hypot(sf / f, float(ev.speed_sigma_m_s or 0.0) / v)
    wlo, whi = wlo - widen, whi + widen
    if ev.nominal_pitch_m is not None:
        nom = float(ev.nominal_pitch_m)
        el = 100.0 * (p / nom - 1.0)
        ok = wlo <= el <= whi
        checks["plausible"] = bool(ok)
        if ok:
            return None
        v_nom = f * nom
        return Decision(
            STATUS_IMPLAUSIBLE,
            (
                f"the family at {f:.4g} Hz implies a pitch of {_mm(p)} at {v:g} m/s ({ev.speed_source}), an elongation "
                f"of {el:+.1f} % of the nominal {_nominal_mm(nom)}, outside the physical window {wlo:+.1f} to {whi:+.1f} %: "
                f"not a verdict. Check the speed (the nominal pitch needs {v_nom:.3g} m/s), the channel (--channel), "
                "the nominal pitch, or whether the sensor was on this machine's step chain"
            ),
            implied_pitch_m=p,
            checks=checks,
        )
    c, dev = nearest_catalogue(p, catalogue)
    ok = wlo <= dev <= whi
    checks["plausible"] = bool(ok)
    if ok:
        return None
    return Decision(
        STATUS_IMPLAUSIBLE,
        (
            f"the family at {f:.4g} Hz implies a pitch of {_mm(p)} at {v:g} m/s ({ev.speed_source}), {dev:+.1f} % "
            f"from the nearest standard step-chain pitch {_nominal_mm(c)} (standard: "
            f"{', '.join(f'{1000 * q:.2f}' for q in catalogue)} mm; window {wlo:+.1f} to {whi:+.1f} %): not a step "
            "chain's link pass. Check the speed, the channel (--channel), give --nominal-pitch, or check "
            "that the recording is of an escalator"
        ),
        implied_pitch_m=p,
        checks=checks,
    )


def _inconclusive(ev, p, checks, reason):
    """``inconclusive`` with ``reason``: the pitch ``p`` given, no verdict (``"inconclusive"`` where a nominal pitch
    asked for one)."""
    return Decision(
        STATUS_INCONCLUSIVE,
        reason,
        verdict="inconclusive" if ev.nominal_pitch_m is not None else None,
        implied_pitch_m=p,
        checks=checks,
    )


def _check_harmonics(ev, p, checks):
    """``inconclusive`` for one spectral line without a significant harmonic; None otherwise (or unknown)."""
    if ev.significant_orders is None:
        return None
    harmonics = len(set(ev.significant_orders) - {1}) >= 1
    checks["harmonics"] = bool(harmonics)
    if harmonics:
        return None
    return _inconclusive(
        ev,
        p,
        checks,
        (
            f"one spectral line at {float(ev.fundamental_hz):.4g} Hz (pitch {_mm(p)}) without a significant "
            "harmonic: a tone (a structural mode, a motor, a fan) cannot be told from a link pass, whose roller "
            "impacts give harmonics; no verdict"
        ),
    )


def _check_methods_agree(ev, p, checks):
    """``inconclusive`` when the spectral and the mean-phase estimates differ by more than
    :data:`DISAGREE_SIGMAS` and by more than :data:`MAX_PART_WANDER` of the frequency: the link-pass phase moves
    within the record (a load changing the speed, or a sensor riding a step round a curve, where the step's own
    link-pass phase shifts); None otherwise (or not checked)."""
    if ev.spectral_hz is None or ev.mean_phase_hz is None or ev.methods_sigmas is None:
        return None
    spectral, mean_phase = float(ev.spectral_hz), float(ev.mean_phase_hz)
    rel = abs(spectral - mean_phase) / float(ev.fundamental_hz)
    agree = rel <= MAX_PART_WANDER or ev.methods_sigmas <= DISAGREE_SIGMAS
    checks["estimates agree"] = bool(agree)
    if agree:
        return None
    return _inconclusive(
        ev,
        p,
        checks,
        (
            f"the spectral ({spectral:.5g} Hz) and mean-phase ({mean_phase:.5g} Hz) estimates differ by "
            f"{100 * rel:.2g} % ({ev.methods_sigmas:.0f} sigma; pitch {_mm(p)}): the link-pass phase moves within "
            f"the record more than a chain under speed control does ({100 * MAX_PART_WANDER:g} %), as when the load "
            "changes the speed or a sensor riding a step goes round a curve (the step's own link-pass phase shifts "
            "there); record the straight ride or a fixed sensor; no verdict"
        ),
    )


def _check_parts_wander(ev, p, checks):
    """``inconclusive`` when the frequency wanders between parts of the record more than :data:`MAX_PART_WANDER`
    (a gait, a cadence: no speed given as one number matches it); None otherwise (or not checked)."""
    if ev.part_wander is None:
        return None
    steady = ev.part_wander <= MAX_PART_WANDER
    checks["steady between parts"] = bool(steady)
    if steady:
        return None
    return _inconclusive(
        ev,
        p,
        checks,
        (
            f"the frequency wanders {100 * ev.part_wander:.2g} % between parts of the record ({ev.part_summary}; "
            f"pitch {_mm(p)}): more than a chain under speed control ({100 * MAX_PART_WANDER:g} %), as a gait or a "
            "cadence does; no speed given as one number matches it, no verdict"
        ),
    )


def _verdict(ev, p, checks):
    """``ok`` with the elongation verdict when the elongation is resolved to :data:`EVIDENCE_FRACTION` of the
    first limit, else ``inconclusive``; ``ok`` without a verdict when there is no nominal pitch."""
    f = float(ev.fundamental_hz)
    if ev.nominal_pitch_m is None:
        return Decision(
            STATUS_OK,
            f"link-pass family at {f:.4g} Hz, pitch {_mm(p)} (no nominal pitch: no verdict)",
            implied_pitch_m=p,
            checks=checks,
        )
    nom, v = float(ev.nominal_pitch_m), float(ev.speed_m_s)
    el = 100.0 * (p / nom - 1.0)
    sf = float(ev.fundamental_sigma_hz)
    sf = sf if math.isfinite(sf) else 0.0
    lim = check_limits(ev.limits_percent)
    rel = math.hypot(sf / f, float(ev.speed_sigma_m_s or 0.0) / v)
    el_sigma = 100.0 * p * rel / nom
    need = EVIDENCE_FRACTION * lim[0]
    resolved = el_sigma <= need
    checks["resolved"] = bool(resolved)
    stated = ev.speed_sigma_m_s is not None  # not stated: el_sigma is the frequency's part only, a lower bound
    if not resolved:
        why = (
            f"elongation {fmt_pm(el, el_sigma, sign=True)} %: its sigma is {SIGMA_TOO_LARGE} "
            if stated
            else f"elongation {el:+z.2f} % ({SPEED_SIGMA_NOT_STATED}): the frequency's part of its sigma alone, "
            f"{el_sigma:.2g} %, is {SIGMA_TOO_LARGE} "
        )
        speed_part = float(ev.speed_sigma_m_s or 0.0) / v
        if stated and speed_part > sf / f:
            # what the record can tell instead: the chain's actual speed from the link pass and the nominal pitch
            sv = f * nom * sf / f
            why += (
                f"({need:.2g} %): the speed's uncertainty ({100 * speed_part:.2g} %) covers the elongation; the link "
                f"pass and the nominal pitch give the chain's actual speed {fmt_pm(f * nom, sv)} m/s, "
                f"{fmt_pm(100 * (f * nom / v - 1), 100 * sv / v, sign=True)} % from the {v:g} m/s given; measure the "
                "speed on a step (a tachometer) for an elongation verdict"
            )
            return Decision(STATUS_INCONCLUSIVE, why, verdict="inconclusive", implied_pitch_m=p, checks=checks)
        return Decision(
            STATUS_INCONCLUSIVE,
            f"{why}({need:.2g} %); record longer, or measure the speed better, for a verdict",
            verdict="inconclusive",
            implied_pitch_m=p,
            checks=checks,
        )
    verdict = elongation_verdict(el, lim)
    return Decision(
        STATUS_OK,
        (
            f"elongation {fmt_pm(el, el_sigma, sign=True)} % of {_nominal_mm(nom)}: {verdict}"
            if stated
            else f"elongation {el:+z.2f} % of {_nominal_mm(nom)}: {verdict} ({SPEED_SIGMA_NOT_STATED})"
        ),
        verdict=verdict,
        implied_pitch_m=p,
        checks=checks,
    )
