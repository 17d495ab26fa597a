"""One speed per run: the chain (step) speed that every number of a command or a report uses, resolved once.

:func:`resolve_speed` takes the speed given (``--speed``), else the escalator profile's rated speed, else the
speed the recording states, else the scene's nominal speed, with its standard deviation and where each came
from.  A speed given without an uncertainty keeps ``sigma=None``: it is *not stated*, and what is derived
from it says so instead of printing ``+- 0``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..model.profile import STANDARD_SPEED_TOLERANCE
from ..model.schema import nominal_speed
from .decision import DEFAULT_LIMITS_PERCENT
from .rounding import SPEED_SIGMA_NOT_STATED, fmt_pm

__all__ = ["ResolvedSpeed", "resolve_speed", "speed_from_recording", "speed_part_too_large"]


#: the source of a speed taken from the scene, nothing else stating one
SCENE_SOURCE = "the scene's nominal speed"
#: a metadata key or a channel named as a speed
_SPEED_KEY = re.compile(r"(speed|velocidad|velocity|geschwindigkeit|vitesse|velocita)", re.IGNORECASE)


def speed_from_recording(recording):
    """``(speed [m/s], source)`` that the recording states in its metadata, or ``(None, None)``.

    Keys ending in ``_m_s`` that name a speed (``chain_speed_m_s``, ``velocidad_m_s``, ``speed_m_s``)
    count; the source names the key, e.g. ``"file: chain_speed_m_s"``. Else a channel along time named as a speed,
    in m/s as read (a tachometer's, written in km/h or m/min too): its mean, ``"file: mean of channel speed"``.
    """
    for key in sorted(recording.attrs, key=lambda k: (k != "chain_speed_m_s", k)):
        if not (str(key).endswith("_m_s") and _SPEED_KEY.search(str(key))):
            continue
        try:
            v = float(recording.attrs[key])
        except (TypeError, ValueError):
            continue
        if math.isfinite(v) and v > 0:
            return v, f"file: {key}"
    # a speed channel (a tachometer's, in m/s as read): its mean over the record, where it reads a chain's speed
    # steadily (a vibration velocity swings about zero: not a speed)
    for name in recording.data_vars:
        da = recording[name]
        if da.dims == ("time",) and str(da.attrs.get("units", "")) == "m/s" and _SPEED_KEY.search(str(name)):
            vals = np.asarray(da.values, dtype=float)
            vals = vals[np.isfinite(vals)]
            if vals.size < 2:
                continue
            mean = abs(float(vals.mean()))
            if not (SPEED_CHANNEL_RANGE[0] <= mean <= SPEED_CHANNEL_RANGE[1] and float(vals.std()) < 0.1 * mean):
                continue
            # to four digits: a tachometer's calibration, not the mean's noise, bounds what it states
            return float(f"{mean:.4g}"), f"file: mean of channel {name}"
    return None, None


#: a speed channel's mean is the chain's speed only within this range [m/s] (steps and moving walks)
SPEED_CHANNEL_RANGE = (0.05, 3.0)


@dataclass(frozen=True)
class ResolvedSpeed:
    """The run's chain speed.

    Attributes
    ----------
    value : float or None
        [m/s]; None when nothing states a speed.
    sigma : float or None
        Its standard deviation [m/s]; None: not stated.
    source, sigma_source : str
        Where each came from (``"given"``, ``"escalator profile E07"``, ``"file: chain_speed_m_s"`` ...).
    """

    value: float | None
    sigma: float | None = None
    source: str = ""
    sigma_source: str = ""

    @property
    def from_scene(self) -> bool:
        """Whether the speed is the scene's own, assumed because nothing else states one (a pitch read at it is
        the scene's by construction: not judged)."""
        return self.source.startswith(SCENE_SOURCE)

    @property
    def text(self) -> str:
        """``0.5000 +- 0.0003 m/s (given)`` or ``0.5 m/s (given; speed uncertainty not stated)``."""
        if self.value is None:
            return "not known (give --speed)"
        if self.sigma is None:
            return f"{self.value:g} m/s ({self.source}; {SPEED_SIGMA_NOT_STATED})"
        if not self.sigma > 0:  # stated as exact: kept as zero, not read as "not stated"
            why = "" if self.sigma_source in ("", "given") else f"; sigma: {self.sigma_source}"
            return f"{self.value:g} +- 0 m/s ({self.source}{why}; stated as exact)"
        why = "" if self.sigma_source in ("", "given") else f"; sigma: {self.sigma_source}"
        return f"{fmt_pm(self.value, self.sigma, 'm/s')} ({self.source}{why})"

    def as_dict(self) -> dict:
        return {
            "speed_m_s": self.value,
            "speed_sigma_m_s": self.sigma,
            "speed_source": self.source,
            "speed_sigma_source": self.sigma_source if self.sigma is not None else SPEED_SIGMA_NOT_STATED,
        }


def scene_speed(scene):
    """The nominal chain speed of an inverse or forward scene [m/s]; None for a kinematics scene or a speed of 0."""
    if scene is None:
        return None
    if scene.analysis == "inverse":
        return float(scene.motion.speed)
    if scene.analysis == "forward":
        return float(nominal_speed(scene.effects, scene.run)) or None
    return None


def resolve_speed(speed=None, speed_sigma=None, *, profile=None, recording=None, scene=None) -> ResolvedSpeed:
    """The run's speed: ``speed`` [m/s], else the profile's, else the recording's stated one, else the scene's.

    ``speed_sigma`` [m/s, or a text like ``"0.05%"`` of the speed used] is the stated standard deviation of whichever speed is used; without it a profile's
    speed takes the profile's (``Profile.speed_sigma``: stated, or the escalator standard's tolerance of a
    rated speed), and any other speed has none (``sigma=None``: not stated).

    Raises
    ------
    ValueError
        A speed that is not positive, or a negative sigma.
    """
    if isinstance(speed_sigma, str) and speed_sigma.strip().endswith("%"):  # a percentage of the speed used
        base = resolve_speed(speed, None, profile=profile, recording=recording, scene=scene)
        if base.value is None:
            return base
        try:
            speed_sigma = float(speed_sigma.strip()[:-1]) / 100.0 * base.value
        except ValueError:
            raise ValueError(f"speed_sigma: expected m/s or a percentage like 0.1%, got {speed_sigma!r}") from None
    if speed_sigma is not None:
        speed_sigma = float(speed_sigma)
        if not (math.isfinite(speed_sigma) and speed_sigma >= 0):
            raise ValueError(f"speed_sigma must be >= 0 m/s, got {speed_sigma!r}")
    stated = (speed_sigma, "given") if speed_sigma is not None else (None, "")
    if speed is not None:
        v = float(speed)
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"speed must be a positive number of m/s, got {speed!r}")
        return ResolvedSpeed(v, *stated[:1], source="given", sigma_source=stated[1])
    if profile is not None and getattr(profile, "speed", None):
        rated = ", rated" if getattr(profile, "speed_sigma_from_standard", False) else ""
        name = f"{getattr(profile, 'kind', 'escalator')} profile {getattr(profile, 'unit', '')}{rated}"
        if speed_sigma is None:
            sig, why = profile.speed_sigma
            return ResolvedSpeed(float(profile.speed), sig, source=name, sigma_source=why)
        return ResolvedSpeed(float(profile.speed), speed_sigma, source=name, sigma_source="given")
    if recording is not None:
        v, source = speed_from_recording(recording)
        if v is not None:
            return ResolvedSpeed(v, stated[0], source=source, sigma_source=stated[1])
    v = scene_speed(scene)
    if v:
        if speed_sigma is None:
            # a scene's set speed is a rated speed, not one measured on the steps: known to the escalator standard's
            # tolerance, as a profile's rated speed is (its pitch read at it was called "ok" to 0.00 %)
            sig = STANDARD_SPEED_TOLERANCE / math.sqrt(3.0) * v
            why = (
                f"not stated: the scene's set speed taken as a rated speed, known to EN 115-1's +-"
                f"{100 * STANDARD_SPEED_TOLERANCE:g} % (uniform, sigma {100 * STANDARD_SPEED_TOLERANCE / math.sqrt(3):.1f} %)"
            )
            return ResolvedSpeed(v, sig, source=f"{SCENE_SOURCE} ({scene.name})", sigma_source=why)
        return ResolvedSpeed(v, stated[0], source=f"{SCENE_SOURCE} ({scene.name})", sigma_source=stated[1])
    return ResolvedSpeed(None)


def speed_part_too_large(rel_speed_sigma, elongation_percent=None, limits_percent=None, *, z=1.96, fraction=1 / 3):
    """Whether the speed's relative sigma is too large for the decision at hand.

    With an elongation and its limits: when ``z`` times the speed's part of the elongation's sigma reaches the
    nearest limit (the verdict could change within the speed's uncertainty).  Without them: when the speed's
    part exceeds ``fraction`` of the first limit (the decision's own rule for a resolved elongation; 0.5 % of
    the default 1.5 %).
    """
    if rel_speed_sigma is None or not rel_speed_sigma > 0:
        return False
    part = 100.0 * float(rel_speed_sigma)
    limits = tuple(limits_percent) if limits_percent is not None else DEFAULT_LIMITS_PERCENT
    if part > fraction * limits[0]:
        return True
    if elongation_percent is None or not math.isfinite(float(elongation_percent)):
        return False
    distance = min(abs(float(elongation_percent) - lim) for lim in limits)
    return z * part >= distance
