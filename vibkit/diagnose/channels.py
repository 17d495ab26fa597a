"""Every vibration channel of a recording, one decision for the recording.

:func:`estimate_channels` runs :func:`vibkit.diagnose.pitch.estimate_pitch` on every vibration channel
(or the one asked for; a sparse channel on its own samples, :func:`vibkit.io.channels.own_samples`) and
combines them: the result comes from the channels where the link pass is
found (status ``ok`` or ``inconclusive``); when several are, their fundamentals must agree within
:data:`CONSISTENCY_SIGMAS` combined sigmas (else the recording is refused as ``implausible``: two
periodicities, not one chain), and the channel with the most evidence (detection statistic over its threshold) gives the numbers. A vibkit
simulation is one chain: its sensor decides alone (:func:`decision_channels`).

:func:`~vibkit.diagnose.speed.speed_from_recording` (re-exported here) finds a chain speed the file states (Leon's ``chain_speed_m_s``, a
Spanish sheet's ``Velocidad (m/s)``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..io.channels import COUNTER_ATTR, STATUS_ATTR, is_status, own_samples
from .decision import EXIT_CODES, STATUS_IMPLAUSIBLE, STATUS_NOT_FOUND
from .pitch import estimate_pitch, pick_channel
from .speed import _SPEED_KEY, speed_from_recording  # noqa: F401 (speed_from_recording: re-exported)

__all__ = [
    "CONSISTENCY_SIGMAS",
    "ChannelsResult",
    "decision_channels",
    "estimate_channels",
    "speed_from_recording",
    "vibration_channels",
]

#: channels whose fundamentals differ by more than this many combined sigmas are not one chain
CONSISTENCY_SIGMAS = 5.0
#: units of a channel named as a speed that is a speed channel, not a vibration: a chain's (m/s) or a sprocket's
#: or motor's angular speed (a gyroscope's rad/s is not named a speed and stays a vibration channel)
_SPEED_UNITS = ("m/s", "rad/s", "rpm", "1/min", "deg/s")
_TIME_NAME = re.compile(r"(^|_)(time|timestamp|elapsed|seconds|epoch|date)(_|$)", re.IGNORECASE)


#: a simulation's numerical diagnostics, not signals of the machine: the closure residual is rounding
#: (1e-14 m), and its pattern repeats with the link pass like everything else in a simulation
SOLVER_DIAGNOSTICS = ("closure_residual",)
_ANALYSES = ("kinematics", "inverse", "forward")
#: what a simulation's decision reads, the first group present: the tensioner's displacement sensor (fixed, it
#: sees every link at one place: its link pass is the chain's), else a step accelerometer. A simulation is one
#: chain; its other outputs (forces, torques, energies) are the model's, not a sensor's, and each reads the link
#: pass with a bias of its own at a sigma of microhertz, so that two of them would always "disagree"
SIMULATED_SENSORS = (("tensioner_displacement", "delta"), ("accel_step",))


def _simulated(recording) -> bool:
    return recording.attrs.get("analysis") in _ANALYSES and "scene" in recording.attrs


def counted_part(recording):
    """``(recording, note)``: a vibkit simulation that counted its speed after its start-up from rest
    (``speed_counted_from_s``) from that time on, with a note saying so; any other recording as it is, note None.

    The link pass read over the start-up as well is the whole run's mean, below the speed counted after it: a
    new chain read 0.8 % long."""
    t_from = recording.attrs.get("speed_counted_from_s")
    if not _simulated(recording) or t_from is None or "time" not in recording.dims:
        return recording, None
    t = np.asarray(recording["time"].values, dtype=float)
    if not t.size or float(t_from) <= t[0]:
        return recording, None
    part = recording.isel(time=np.flatnonzero(t >= float(t_from)))
    return (
        part,
        f"the simulation's start-up from rest (before {float(t_from):.1f} s) left out: its speed is counted after it",
    )


def decision_channels(recording) -> list:
    """The channels whose link pass decides: every :func:`vibration_channels` one of a recording; of a vibkit
    simulation, its sensor (:data:`SIMULATED_SENSORS`), or all of them where it has none."""
    chans = vibration_channels(recording)
    if _simulated(recording):
        for group in SIMULATED_SENSORS:
            present = [c for c in group if c in chans]
            if present:
                return present[:1]
    return chans


def vibration_channels(recording) -> list:
    """Channels that may carry a vibration: along time, not the burst number, not a sample counter, not
    a clock or a speed (a chain's or a sprocket's: :data:`_SPEED_UNITS`), not a barometer's, not a status column (an accuracy
    code, a column that never changes), not a simulation's numerical diagnostic (:data:`SOLVER_DIAGNOSTICS`)."""
    simulated = _simulated(recording)
    out = []
    for v in recording.data_vars:
        da = recording[v]
        if v == "segment" or da.dims != ("time",) or da.attrs.get(COUNTER_ATTR):
            continue
        if simulated and v in SOLVER_DIAGNOSTICS:
            continue
        if int(da.attrs.get(STATUS_ATTR, 0)) or is_status("", da.values):
            continue
        units = str(da.attrs.get("units", ""))
        if da.attrs.get("sensor") == "barometer":  # a phone's air pressure and altitude: its rides' rise, no vibration
            continue
        if (
            units in ("s", "ms", "us", "ns")
            or _TIME_NAME.search(str(v))
            or (units in _SPEED_UNITS and _SPEED_KEY.search(str(v)))
        ):
            continue
        out.append(str(v))
    return out


#: the pitch fields of a channel's row (:meth:`vibkit.diagnose.pitch.PitchEstimate.pitch_fields`)
_ROW_PITCH_KEYS = ("pitch_m", "pitch_sigma_m", "elongation_percent", "elongation_sigma_percent", "verdict")


@dataclass(frozen=True)
class ChannelsResult:
    """Per-channel estimates and the recording's decision.

    Attributes
    ----------
    status, reason : str
        The recording's status (as :mod:`vibkit.diagnose.decision`) and why.
    best : PitchEstimate or None
        The channel that gives the numbers (None when refused).
    estimates : list of PitchEstimate
    errors : dict
        Channel -> message, for channels that could not be analysed (too short ...).
    """

    status: str
    reason: str
    best: object = None
    estimates: list = field(default_factory=list)
    errors: dict = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        return EXIT_CODES[self.status]

    def per_channel(self) -> list:
        """One short JSON-ready row per channel."""
        rows = []
        for e in self.estimates:
            r = {"channel": e.channel, "status": e.status, "reason": e.reason}
            if e.has_link_pass:
                r.update(fundamental_hz=e.fundamental_hz, fundamental_sigma_hz=e.fundamental_sigma_hz)
                pf = e.pitch_fields()  # as the estimate's JSON: null sigmas without a stated speed uncertainty
                r.update({k: pf[k] for k in _ROW_PITCH_KEYS if k in pf})
            elif e.decision is not None and e.decision.implied_pitch_m is not None:
                r["implied_pitch_m"] = e.decision.implied_pitch_m
            rows.append(r)
        rows += [{"channel": c, "status": "error", "reason": m} for c, m in self.errors.items()]
        return rows


def estimate_channels(recording, *, channel=None, sensors=None, **kwargs) -> ChannelsResult:
    """:func:`estimate_pitch` on ``channel``, or on every :func:`decision_channels` one, combined.

    ``sensors`` (channel -> :class:`vibkit.diagnose.sensors.ChannelSensor`, as a run's settings resolve them) gives
    each channel its own sensor; a channel not in it has the one its quantity says.

    Raises
    ------
    ValueError
        ``channel`` is given and cannot be analysed, or no channel can be analysed at all.
    """
    recording, cut = counted_part(recording)
    names = [pick_channel(recording, channel)] if channel is not None else decision_channels(recording)
    if not names:
        names = [pick_channel(recording, None)]
    ests, errors = [], {}
    for name in names:
        try:
            sensor = (sensors or {}).get(name)
            ests.append(estimate_pitch(own_samples(recording, name), channel=name, sensor=sensor, **kwargs))
        except ValueError as exc:
            if channel is not None or len(names) == 1:
                raise
            errors[name] = " ".join(str(exc).split())
    if cut:
        for e in ests:
            e.notes.insert(0, cut)
    if not ests:
        raise ValueError("no channel could be analysed: " + "; ".join(f"{c}: {m}" for c, m in errors.items()))
    found = [e for e in ests if e.has_link_pass]
    if not found:
        status = STATUS_IMPLAUSIBLE if any(e.status == STATUS_IMPLAUSIBLE for e in ests) else STATUS_NOT_FOUND
        if len(ests) == 1:
            reason = ests[0].reason
        else:
            reason = "no channel carries the link pass: " + "; ".join(f"{e.channel}: {e.reason}" for e in ests)
        return ChannelsResult(status, reason, None, ests, errors)
    best = max(found, key=_evidence)
    bad = [
        e
        for e in found
        if e is not best
        and abs(e.fundamental_hz - best.fundamental_hz)
        > CONSISTENCY_SIGMAS * math.hypot(_agreement_sigma(e), _agreement_sigma(best))
    ]
    if bad:
        listing = ", ".join(
            f"{e.channel} {e.fundamental_hz:.5g} +- {e.fundamental_sigma_hz:.2g} Hz" for e in [best] + bad
        )
        return ChannelsResult(
            STATUS_IMPLAUSIBLE,
            (
                f"the channels disagree ({listing}; more than {CONSISTENCY_SIGMAS:g} sigma apart): two periodicities, "
                "not one chain; choose the channel on the chain with --channel"
            ),
            None,
            ests,
            errors,
        )
    reason = best.reason
    if len(found) > 1:
        reason += (
            f"; channels {', '.join(e.channel for e in found)} see the same link pass "
            f"(within {CONSISTENCY_SIGMAS:g} sigma), numbers from {best.channel} (the most evidence: its detection "
            "statistic furthest over its threshold)"
        )
    return ChannelsResult(best.status, reason, best, ests, errors)


def _evidence(e):
    """How strongly a channel's record shows its link pass: its detection statistic over the statistic's
    threshold (the harmonic sum's, at the same false-alarm probability), then the smaller frequency sigma.  A
    phone's lateral axis can carry a faint line whose formal sigma is the smallest of the three (its noise is
    small too) while the travel and vertical axes carry the family: the numbers come from the evidence."""
    det = e.detection or {}
    stat, thr = det.get("statistic"), det.get("threshold")
    ratio = float(stat) / float(thr) if stat is not None and thr and math.isfinite(float(thr)) else 0.0
    return (ratio if math.isfinite(ratio) else 0.0, -float(e.fundamental_sigma_hz))


def _agreement_sigma(e):
    """A channel's frequency sigma for the channels' agreement, with what its sigma does not cover where its
    frequency moves within the record:

    * its own spectral and mean-phase estimates disagree (its decision's check "estimates agree" failed, as on a
      step going round a curve): the largest difference between them;
    * its parts wander (the check "steady between parts" failed): the wander times the frequency.  A simulated
      step accelerometer reads the link pass 0.5 % low, its parts wandering 0.2 %, beside a tensioner that
      reads it to 0.01 %: one chain, not two periodicities."""
    if e.decision is None:
        return e.fundamental_sigma_hz
    sigma = e.fundamental_sigma_hz
    if not e.decision.checks.get("estimates agree", True):
        rows = [r for r in e.per_burst if "mean_phase_hz" in r]
        sigma = math.hypot(sigma, max((abs(r["spectral_hz"] - r["mean_phase_hz"]) for r in rows), default=0.0))
    if not e.decision.checks.get("steady between parts", True):
        sigma = math.hypot(sigma, 0.01 * (e.parts or {}).get("wander_percent", 0.0) * e.fundamental_hz)
    return sigma
