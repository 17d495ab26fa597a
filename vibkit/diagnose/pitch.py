"""Link pitch from a recording: link-pass fundamental, pitch = speed / frequency, elongation.

A roller chain passing a point at speed ``v`` [m/s] with links of pitch ``L`` [m] excites the
link-pass frequency ``f = v / L`` and its harmonics.  :func:`estimate_pitch` finds ``f`` in the
band that a plausible range of pitches allows (octave-safe, :func:`vibkit.signal.link_pass_estimate`),
estimates it below the bin width with its Cramer-Rao standard deviation, burst by burst when the
recording is made of bursts (combined by inverse-variance weighting), and propagates the
uncertainty of ``f`` and of ``v`` to ``L``:

    (sigma_L / L)^2 = (sigma_f / f)^2 + (sigma_v / v)^2

The speed must be measured independently of the chain (a tachometer wheel on a step, not the handrail,
which may run up to 2 % faster; a timed step count).  A speed derived from the motor's rpm and the
*nominal* sprocket returns the nominal pitch by construction: one sprocket turn always moves Z links
whatever their length, so the link-pass frequency is Z times the shaft frequency and
``v_nominal / f = L_nominal``.

:func:`estimate_pitch` runs the steps of :mod:`vibkit.diagnose.pitch_steps` in order: bursts ->
detection -> per-burst estimates -> method -> combination -> parts check (:mod:`vibkit.diagnose.pitch_parts`:
the sigma against the record's own spread, the source's wander) -> pitch -> decision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..io.channels import resolve_channel
from ..signal.bursts import Burst, uniform_bursts
from . import pitch_steps as steps
from .decision import (
    CATALOGUE_PITCHES_M,
    DEFAULT_LIMITS_PERCENT,
    STATUS_IMPLAUSIBLE,
    STATUS_INCONCLUSIVE,
    STATUS_NOT_FOUND,
    STATUS_OK,
    Decision,
    LinkPassEvidence,
    check_limits,
    decide,
    elongation_verdict,
)
from .html import result_table_html
from .pitch_jitter import jitter_effect
from .pitch_parts import check_parts
from .pitch_steps import Hypothesis
from .rounding import SPEED_SIGMA_NOT_STATED, fmt_pm
from .sensors import ChannelSensor, channel_sensor
from .settings import DEFAULT_LINKS_PER_STEP, DEFAULT_TEETH

if TYPE_CHECKING:  # for the annotations only
    import xarray as xr

__all__ = [
    "CATALOGUE_PITCHES_M",
    "DEFAULT_LIMITS_PERCENT",
    "DEFAULT_PITCH_RANGE_M",
    "Burst",
    "Hypothesis",
    "PitchEstimate",
    "STATUS_IMPLAUSIBLE",
    "STATUS_INCONCLUSIVE",
    "STATUS_NOT_FOUND",
    "STATUS_OK",
    "elongation_verdict",
    "estimate_pitch",
    "pick_channel",
    "uniform_bursts",
]

#: plausible link pitches [m]; the link-pass search band is speed / this range
DEFAULT_PITCH_RANGE_M = (0.08, 0.2)
#: step length of the reference escalator (3 links) [m]
STEP_LENGTH_M = 0.4
#: false-alarm probability of the link-pass detection test
DEFAULT_P_FA = 1e-3


def pick_channel(recording, channel=None) -> str:
    """Name of the channel to analyse: ``channel`` (vibkit's name or the file's header), else the first
    that is not a sample counter (see :func:`vibkit.io.resolve_channel`).

    Raises
    ------
    ValueError
        ``channel`` is not a channel of the recording, or the recording has no channel.
    """
    return resolve_channel(recording, channel)


#: what a result of a sensor riding a step says: its link pass turns half a cycle at each head (the fundamental,
#: opposite on the two runs) and reads off the chain's by 0.06-1.3 % on the simulated study escalator (12 s to
#: three loops), more than its sigma says (docs/explanation/limits.md)
STEP_WARNING = (
    "the sensor rides a step: a step's link pass reads up to about 1 % off the chain's (its fundamental turns "
    "half a cycle at each head), more than this sigma says; a tensioner's elongation is good to its sigma"
)


@dataclass(frozen=True)
class PitchEstimate:
    """Result of :func:`estimate_pitch` (all SI; see :meth:`as_dict` for the JSON form).

    ``detected`` / ``status`` say whether a link-pass family was found at all (``"ok"`` or
    ``"no link-pass found"``; then every frequency and pitch field is NaN).  ``method`` is
    ``"spectral"`` (harmonic least squares, stationary record) or ``"mean-phase"`` (total tracked phase
    over the time, when the frequency wanders), with ``method_reason``.
    """

    channel: str
    speed_m_s: float
    speed_sigma_m_s: float
    fundamental_hz: float
    fundamental_sigma_hz: float
    pitch_m: float
    pitch_sigma_m: float
    band_hz: tuple
    harmonics: list
    per_burst: list
    hypotheses: list
    warnings: list
    notes: list
    nominal_pitch_m: float | None = None
    elongation_percent: float | None = None
    elongation_sigma_percent: float | None = None
    limits_percent: tuple = DEFAULT_LIMITS_PERCENT
    verdict: str | None = None
    snr_db: float = float("nan")
    chi2_per_dof: float = float("nan")
    extra: dict = field(default_factory=dict)
    detected: bool = True
    status: str = STATUS_OK
    detection: dict = field(default_factory=dict)
    method: str = "spectral"
    method_reason: str = ""
    invalid_samples: dict = field(default_factory=dict)
    decision: Decision | None = None
    speed_source: str = "given"
    parts: dict = field(default_factory=dict)

    @property
    def speed_sigma_stated(self) -> bool:
        """Whether the speed's uncertainty was stated; if not, ``pitch_sigma_m`` and
        ``elongation_sigma_percent`` hold the frequency's part only (a lower bound)."""
        return self.speed_sigma_m_s is not None

    @property
    def has_link_pass(self) -> bool:
        """Whether a frequency and a pitch may be reported (status ``ok`` or ``inconclusive``)."""
        return self.status in (STATUS_OK, STATUS_INCONCLUSIVE)

    @property
    def reason(self) -> str:
        """Why the status is what it is (the decision's reason)."""
        return self.decision.reason if self.decision is not None else self.detection.get("reason", "")

    def _repr_html_(self) -> str:
        """The notebook's view: status, link pass, speed, pitch and elongation, each with its sigma."""
        rows: list[tuple[str, object]] = [("channel", self.channel), ("status", self.status)]
        if self.has_link_pass:
            rows += [
                ("link-pass frequency", fmt_pm(self.fundamental_hz, self.fundamental_sigma_hz, "Hz")),
                ("chain speed", fmt_pm(self.speed_m_s, self.speed_sigma_m_s, "m/s")),
                ("link pitch", fmt_pm(self.pitch_m * 1e3, self.pitch_sigma_m * 1e3, "mm")),
            ]
            if self.elongation_percent is not None:
                rows.append(("elongation", fmt_pm(self.elongation_percent, self.elongation_sigma_percent, "%")))
        rows += [("verdict", self.verdict or "none"), ("reason", self.reason)]
        return result_table_html(f"Link pitch of {self.channel}: {self.verdict or self.status}", rows)

    def as_dict(self) -> dict:
        """Plain JSON-ready dict (keys carry units).

        Without a detected link-pass family (``status == "no link-pass found"``) the dict has no
        frequency, pitch or elongation keys at all: there is no number to report; a frequency-only
        estimate (no speed) has no pitch or elongation keys (:meth:`pitch_fields`).
        """
        head = {
            "status": self.status,
            "reason": self.reason,
            "detected": self.detected,
            "detection": dict(self.detection),
            "invalid_samples": dict(self.invalid_samples),
        }
        if not self.has_link_pass:
            d = {
                "channel": self.channel,
                **head,
                "speed_m_s": self.speed_m_s,
                "speed_source": self.speed_source,
                "band_hz": list(self.band_hz),
                "warnings": list(self.warnings),
                "notes": list(self.notes),
            }
            if self.decision is not None and self.decision.implied_pitch_m is not None:
                d["implied_pitch_m"] = self.decision.implied_pitch_m  # what the refused family would mean
            return d
        d = {
            **head,
            "method": self.method,
            "method_reason": self.method_reason,
            "channel": self.channel,
            "speed_m_s": self.speed_m_s,
            "speed_source": self.speed_source,
            "band_hz": list(self.band_hz),
            "fundamental_hz": self.fundamental_hz,
            "fundamental_sigma_hz": self.fundamental_sigma_hz,
            "snr_db": self.snr_db,
            "harmonics": [dict(h) for h in self.harmonics],
            "bursts": [dict(b) for b in self.per_burst],
            "burst_chi2_per_dof": None if math.isnan(self.chi2_per_dof) else self.chi2_per_dof,
            "parts": dict(self.parts),
            "hypotheses": [vars(h).copy() for h in self.hypotheses],
            "warnings": list(self.warnings),
            "notes": list(self.notes),
        }
        d.update(self.pitch_fields())
        return d

    def pitch_fields(self) -> dict:
        """The speed's sigma, the pitch and (with a nominal pitch) the elongation and verdict, JSON-ready, as
        :meth:`as_dict` gives them (``vibkit spectrum`` with a speed adds these to its own): without a stated
        speed uncertainty the sigmas are null, ``uncertainty`` says why and the ``*_frequency_only`` keys give
        the frequency's part.  Empty without a link pass, or for a frequency-only estimate (no speed)."""
        if not self.has_link_pass or self.extra.get("frequency_only"):
            return {}
        stated = self.speed_sigma_stated
        d: dict[str, object] = {
            "speed_sigma_m_s": self.speed_sigma_m_s,
            "pitch_m": self.pitch_m,
            "pitch_sigma_m": self.pitch_sigma_m if stated else None,
        }
        if self.nominal_pitch_m is not None:
            d.update(
                nominal_pitch_m=self.nominal_pitch_m,
                elongation_percent=self.elongation_percent,
                elongation_sigma_percent=self.elongation_sigma_percent if stated else None,
                limits_percent=list(self.limits_percent),
                verdict=self.verdict,
            )
        if not stated:  # null sigmas, with the reason and the part that is known
            d["uncertainty"] = (
                f"{SPEED_SIGMA_NOT_STATED}: the pitch's and the elongation's sigmas are unknown; "
                "the *_frequency_only keys give the frequency's part, a lower bound"
            )
            d["pitch_sigma_frequency_only_m"] = self.pitch_sigma_m
            if self.nominal_pitch_m is not None:
                d["elongation_sigma_frequency_only_percent"] = self.elongation_sigma_percent
        return d


def estimate_pitch(
    recording: xr.Dataset,
    *,
    speed: float,
    speed_sigma: float | None = None,
    channel: str | None = None,
    band: tuple[float, float] | None = None,
    nominal_pitch: float | None = None,
    limits_percent: tuple[float, float, float] = DEFAULT_LIMITS_PERCENT,
    pitch_range: tuple[float, float] = DEFAULT_PITCH_RANGE_M,
    n_harmonics: int = 5,
    teeth: int = DEFAULT_TEETH,
    p_fa: float = DEFAULT_P_FA,
    speed_source: str = "given",
    frequency_only: bool = False,
    n_links: int | None = None,
    links_per_step: int = DEFAULT_LINKS_PER_STEP,
    on_step: bool | None = None,
    sensor: ChannelSensor | None = None,
) -> PitchEstimate:
    """Link pitch from a recording's link-pass frequency and an independently measured speed.

    Parameters
    ----------
    recording : xarray.Dataset
        A recording (see :func:`vibkit.read_recording`), continuous or in bursts, uniformly
        sampled or not.
    speed : float
        Chain (step) speed. [m/s]
    speed_sigma : float or None, optional
        Standard deviation of ``speed`` [m/s]; None: not stated (the pitch's and the elongation's sigmas
        are then the frequency's part only, and :meth:`PitchEstimate.as_dict` gives them as null with the
        reason).
    channel : str, optional
        Channel to analyse (default: the first).
    band : (float, float), optional
        Search band of the link-pass fundamental. [Hz]  Default: ``speed / pitch_range``.
    nominal_pitch : float, optional
        Nominal link pitch; gives the elongation and a verdict. [m]
    limits_percent : (float, float, float)
        Elongation limits: watch, plan replacement, replace. [%]
    pitch_range : (float, float)
        Plausible pitches. [m]
    n_harmonics : int
        Harmonics fitted.
    teeth : int
        Sprocket teeth (>= 3), for the shaft-frequency hypothesis.
    speed_source : str
        Where ``speed`` came from (``"given"``, ``"file: chain_speed_m_s"`` ...), named in the result.
    frequency_only : bool
        ``speed`` is a placeholder (``vibkit spectrum`` without a known speed): no plausibility check.
    n_links : int, optional
        Links in the chain (an escalator profile's ``chain.n_links``).  A displacement record (the
        tensioner's) over two loops is then checked for wander against its own once-per-loop pattern, which a
        worn link gives (:func:`vibkit.diagnose.pitch_parts.check_parts`); without it such a pattern reads
        as a wander.  Acceleration channels are checked as without it (``_loop_links``).
    links_per_step : int
        Links (rollers) per step, for the step-pass hypothesis (3, or 4 on 101.6 mm chains).
    on_step : bool, optional
        The sensor rides a step (an escalator profile's ``sensor.kind = "step"``); default: a channel named
        ``accel_step`` (vibkit's simulated step).  Its link pass can read up to about 1 % off the chain's,
        more than its sigma says (:data:`STEP_WARNING`): the result warns.  Given, it overrides ``sensor``'s.
    sensor : vibkit.diagnose.sensors.ChannelSensor, optional
        The channel's sensor (:func:`vibkit.diagnose.sensors.channel_sensor`, with the escalator profile's sensors);
        default: the channel's own (its quantity; vibkit's simulated ``accel_step`` rides a step).  Whether it rides
        a step gives the warning above; whether it is the tensioner's displacement, the parts check with ``n_links``.
    p_fa : float
        False-alarm probability of the detection test run first
        (:func:`vibkit.signal.detect.detect_link_pass`): without a harmonic family in the band the
        result has ``detected = False``, ``status = "no link-pass found"`` and NaN numbers.

    Returns
    -------
    PitchEstimate
        ``status`` and ``decision`` from :func:`vibkit.diagnose.decision.decide`: a refusal (``"no
        link-pass found"``, ``"implausible"``) has NaN frequency and pitch and no verdict; ``"inconclusive"``
        keeps its numbers with the verdict ``"inconclusive"``.

    Raises
    ------
    ValueError
        Non-positive speed, negative sigma, bad band/limits/range, unknown channel, or no
        fundamental could be estimated.

    Notes
    -----
    Invalid samples (non-finite, fill values ``|x| >= 1e30``, absurd) are excluded as
    :func:`uniform_bursts` says, and counted in ``invalid_samples`` and a warning.  Each burst long
    enough (40 periods) is also tracked in phase; its mean link-pass frequency (total phase over the
    time) replaces the spectral estimate when the frequency wanders
    (:func:`vibkit.diagnose.pitch_steps.choose_methods`).
    ``L = v / f``; ``sigma_L = L sqrt((sigma_f/f)^2 + (sigma_v/v)^2)``.  Bursts are estimated
    separately (never bridged) and combined as ``f = sum(w_i f_i) / sum(w_i)``, ``w_i = 1/sigma_i^2``.
    The elongation is ``100 (L / L_nominal - 1)`` [%].

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> t = np.arange(4000) / 200.0
    >>> rec = xr.Dataset({"x": ("time", np.sin(2 * np.pi * 3.75 * t))}, coords={"time": t})
    >>> round(estimate_pitch(rec, speed=0.5).pitch_m, 4)
    0.1333
    """
    req = _request(speed, speed_sigma, band, nominal_pitch, limits_percent, pitch_range, teeth, p_fa, frequency_only)
    if n_links is not None and (isinstance(n_links, bool) or not isinstance(n_links, (int, np.integer)) or n_links < 2):
        raise ValueError(f"n_links must be an integer >= 2 (links in the chain), got {n_links!r}")
    if isinstance(links_per_step, bool) or not isinstance(links_per_step, (int, np.integer)) or links_per_step < 1:
        raise ValueError(f"links_per_step must be a positive integer, got {links_per_step!r}")
    name = pick_channel(recording, channel)
    if sensor is None or sensor.channel != name:
        sensor = channel_sensor(recording, name)
    prep = steps.prepare_bursts(recording, name, req.band)
    common = _common(recording, name, req, prep, speed_source)
    det = steps.detect(prep, band=req.band, n_harmonics=n_harmonics, p_fa=p_fa, name=name)
    if not det.detected:
        dec = decide(LinkPassEvidence(detected=False, detection_reason=det.reason))
        return _refusal(common, det, dec, [det.reason, *prep.warnings], [], "none", "no link-pass family detected")
    ests, skipped = steps.estimate_bursts(
        prep, name=name, band=req.band, n_harmonics=n_harmonics, f0=float(det.frequency_hz)
    )
    ests = steps.choose_methods(ests)
    comb = steps.combine(ests, name=name)
    parts, sigma = check_parts(ests, comb, n_links=_loop_links(sensor, n_links))
    comb = replace(comb, sigma=sigma)
    jitter_warnings, jitter_notes = jitter_effect(recording, name, ests, req.band, n_harmonics)
    # a widened sigma is a note: the uncertainty stated is then the honest one; a wander too large for a
    # chain is the decision's (inconclusive), not a warning beside a verdict
    warnings = [*prep.warnings, *jitter_warnings, *skipped, *comb.warnings]
    for w in (w for be in ests for w in be.spectral.warnings):
        if w not in warnings:
            warnings.append(w)
    pitch, psig, caveats, notes = steps.pitch_from(comb, req)
    warnings += caveats
    if on_step if on_step is not None else sensor.rides_step:
        warnings.append(STEP_WARNING)
    notes.append(f"parts check: {parts.reason}")
    notes = jitter_notes + parts.warnings + notes
    ev = steps.evidence(det, ests, comb, req, speed_source=speed_source)
    ev = replace(ev, part_wander=parts.wander if parts.checked else None, part_summary=_part_summary(parts))
    dec = decide(ev)
    if not dec.has_link_pass:
        # refused: no frequency, pitch or verdict leaves this function (the reason says what the family implies)
        return _refusal(common, det, dec, [dec.reason, *warnings], notes, comb.method, comb.method_reason)
    if dec.status == STATUS_INCONCLUSIVE:
        warnings.insert(0, f"inconclusive: {dec.reason}")
        if not dec.checks.get("steady between parts", True) and not n_links and _loop_links(sensor, 2):
            notes.append(
                "a worn link's once-a-loop pattern moves the parts' frequency as a wander does: with the chain's "
                "number of links (--links N, or a profile with chain.n_links) a tensioner record over two loops "
                "is checked for wander without it"
            )
    res = dict(
        pitch_m=pitch,
        pitch_sigma_m=psig,
        harmonics=steps.harmonic_rows(ests, comb, prep.scale),
        per_burst=steps.burst_rows(ests),
        hypotheses=steps.hypotheses(
            [be.scaled for be in ests],
            comb.f0,
            req.speed,
            int(teeth),
            req.pitch_range,
            int(links_per_step),
            copies=[None if be.full_rate is None else be.burst for be in ests],
        ),
        warnings=warnings,
        notes=notes,
        detection=det.as_dict(),
        decision=dec,
        status=dec.status,
        parts=parts.as_dict(),
        **common,
    )
    return PitchEstimate(**res, **_numbers(ests, comb, req, pitch, psig, dec))


def _loop_links(sensor: ChannelSensor, n_links):
    """The number of links the parts check aligns its parts with: ``n_links`` on a displacement (the tensioner,
    a fixed sensor) only.  A sensor riding a step reads the link pass low where it goes round the heads, the same
    way every loop (0.5 % on the shipped scene, every place of the loop low): parts aligned with the loops would
    take that for the chain's own pattern, and give a verdict on it."""
    return n_links if n_links and sensor.is_tensioner else None


def _part_summary(parts):
    """The parts' frequencies in a few words, for the decision's reason (empty when not checked)."""
    if not parts.checked:
        return ""
    f = parts.frequencies_hz
    text = f"{parts.n_parts} parts of {parts.part_s:.3g} s give {min(f):.5g}-{max(f):.5g} Hz"
    if parts.n_links and math.isfinite(parts.place_birge):
        text += f"; the wander measured around the places of loops of {parts.n_links} links"
    return text


def _request(speed, speed_sigma, band, nominal_pitch, limits_percent, pitch_range, teeth, p_fa, frequency_only):
    """The arguments of :func:`estimate_pitch` checked (a one-line ValueError naming the first bad one), the
    band defaulting to ``speed / pitch_range``."""
    speed = float(speed)
    if not (math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be a positive number of m/s, got {speed!r}")
    if speed_sigma is not None:  # None: not stated
        speed_sigma = float(speed_sigma)
        if not (math.isfinite(speed_sigma) and speed_sigma >= 0):
            raise ValueError(f"speed_sigma must be >= 0 m/s, got {speed_sigma!r}")
    lo_p, hi_p = (float(v) for v in pitch_range)
    if not 0 < lo_p < hi_p:
        raise ValueError(f"pitch_range must be (min, max) with 0 < min < max [m], got {pitch_range!r}")
    limits = check_limits(limits_percent)
    if isinstance(teeth, bool) or not isinstance(teeth, (int, np.integer)) or teeth < 3:
        raise ValueError(f"teeth must be an integer >= 3 (sprocket teeth), got {teeth!r}")
    if not 0 < float(p_fa) < 0.5:
        raise ValueError(f"p_fa must lie in (0, 0.5), got {p_fa!r}")
    if nominal_pitch is not None and not float(nominal_pitch) > 0:
        raise ValueError(f"nominal_pitch must be a positive length [m], got {nominal_pitch!r}")
    if band is None:
        band = (speed / hi_p, speed / lo_p)
    band = tuple(float(v) for v in band)
    if len(band) != 2 or not 0 < band[0] < band[1]:
        raise ValueError(f"band must be (low, high) with 0 < low < high [Hz], got {band!r}")
    return steps.Request(speed, speed_sigma, band, (lo_p, hi_p), limits, nominal_pitch, teeth, bool(frequency_only))


def _common(recording, name, req, prep, speed_source):
    """The fields every result has, refused or not."""
    extra = {"units": str(recording[name].attrs.get("units", "1")), "frequency_only": req.frequency_only}
    return dict(
        channel=name,
        speed_m_s=req.speed,
        speed_sigma_m_s=req.speed_sigma,
        band_hz=req.band,
        limits_percent=req.limits,
        extra=extra,
        invalid_samples=prep.invalid,
        speed_source=speed_source,
    )


def _numbers(ests, comb, req, pitch, psig, dec):
    """The frequency, its method and fit, and (with a nominal pitch) the elongation and verdict."""
    out = dict(
        fundamental_hz=comb.f0,
        fundamental_sigma_hz=comb.sigma,
        snr_db=float(np.mean([be.spectral.snr_db for be in ests])),
        chi2_per_dof=comb.chi2,
        method=comb.method,
        method_reason=comb.method_reason,
    )
    if req.nominal_pitch is not None and not req.frequency_only:
        nom = float(req.nominal_pitch)
        out.update(
            nominal_pitch_m=nom,
            elongation_percent=100.0 * (pitch / nom - 1.0),
            elongation_sigma_percent=100.0 * psig / nom,
            verdict=dec.verdict,
        )
    return out


def _refusal(common, det, dec, warnings, notes, method, method_reason):
    """A result without frequency, pitch or verdict: no family detected, or the decision refused it."""
    nan = float("nan")
    return PitchEstimate(
        fundamental_hz=nan,
        fundamental_sigma_hz=nan,
        pitch_m=nan,
        pitch_sigma_m=nan,
        harmonics=[],
        per_burst=[],
        hypotheses=[],
        warnings=warnings,
        notes=notes,
        detected=det.detected,
        status=dec.status,
        detection=det.as_dict(),
        method=method,
        method_reason=method_reason,
        decision=dec,
        **common,
    )
