"""A run's settings, resolved once: what every command that analyses a recording analyses it with.

:func:`resolve_settings` builds one frozen :class:`RunSettings` from what the user gives (the command's flags, a
library call's arguments), the escalator profile, the scene simulated beside the recording, and what the recording
itself states, in that order of precedence, and the defaults below.  ``vibkit pitch``, ``spectrum``, ``report``,
``compare``, ``links``, ``ride`` and ``fleet add`` take their speed (with its sigma and where each came from), the
nominal pitch, the sprocket's teeth, the links per step, the chain's number of links, the search band, the
elongation limits, the sensor of each channel (:mod:`vibkit.diagnose.sensors`) and the segment from here, so the
same recording and profile are analysed with the same numbers by each.

The defaults live here and nowhere else: :data:`DEFAULT_TEETH` and :data:`DEFAULT_LINKS_PER_STEP` (the study's
escalator), :data:`DEFAULT_LIMITS_PERCENT` (the elongation limits), :data:`FREQUENCY_ONLY_BAND_HZ` (the band
searched without a speed), :data:`PROFILE_BAND_FACTORS` (the band around a profile's link pass).
:func:`chain_numbers` is the teeth-and-links-per-step part on its own.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from .decision import DEFAULT_LIMITS_PERCENT
from .rounding import fmt_band
from .segment import parse_segment
from .sensors import ChannelSensor, channel_sensor
from .speed import ResolvedSpeed, resolve_speed

__all__ = [
    "DEFAULT_LIMITS_PERCENT",
    "DEFAULT_LINKS_PER_STEP",
    "DEFAULT_TEETH",
    "FREQUENCY_ONLY_BAND_HZ",
    "PROFILE_BAND_FACTORS",
    "RunSettings",
    "SettingsError",
    "chain_numbers",
    "recording_chain",
    "resolve_n_links",
    "resolve_settings",
    "scene_is_unit",
]

#: the study's sprocket: 28 teeth (the shaft hypothesis of a pitch estimate reads them)
DEFAULT_TEETH = 28
#: the study's chain: 3 links per step
DEFAULT_LINKS_PER_STEP = 3
#: the band a link pass is searched in when no speed is known (a step chain at 0.2-0.8 m/s) [Hz]
FREQUENCY_ONLY_BAND_HZ = (2.5, 6.0)
#: the band around a profile's link pass, as factors of speed / nominal pitch: wider than any chain wears,
#: narrow enough to keep the neighbouring periodicities out (:meth:`vibkit.model.profile.Profile.search_band`)
PROFILE_BAND_FACTORS = (0.8, 1.25)


class SettingsError(ValueError):
    """Two sources of one setting that contradict each other; ``parameter`` names the setting (``"n_links"``)."""

    def __init__(self, message, parameter):
        super().__init__(message)
        self.parameter = parameter


@dataclass(frozen=True)
class RunSettings:
    """The settings one run analyses a recording with (see the module doc; every number SI).

    Attributes
    ----------
    speed : ResolvedSpeed
        The chain speed [m/s] with its sigma and where each came from (``value`` None: nothing states one).
    nominal_pitch : float or None
        [m]; ``nominal_pitch_source`` says where it came from.
    teeth, links_per_step : int
        The sprocket's teeth and the chain's links per step.
    n_links : int or None
        Links in the chain; ``n_links_source`` says where the number came from.
    band : (float, float) or None
        The link pass's search band [Hz] (None: the estimator's default, speed over the plausible pitches).
    limits : (float, float, float)
        Elongation limits watch, plan, replace [%].
    sensors : tuple of ChannelSensor
        The sensor of each channel of the recording (:func:`vibkit.diagnose.sensors.channel_sensor`).
    segment : (float, float) or None
        The part of the recording analysed [s, in its own time].
    notes : tuple of str
        What was taken from where, for the user (the profile's values, a link count filled in from geometry).
    """

    speed: ResolvedSpeed
    nominal_pitch: float | None = None
    nominal_pitch_source: str = ""
    teeth: int = DEFAULT_TEETH
    links_per_step: int = DEFAULT_LINKS_PER_STEP
    n_links: int | None = None
    n_links_source: str = ""
    band: tuple[float, float] | None = None
    band_source: str = ""
    limits: tuple[float, float, float] = DEFAULT_LIMITS_PERCENT
    sensors: tuple[ChannelSensor, ...] = ()
    segment: tuple[float, float] | None = None
    notes: tuple[str, ...] = field(default=(), compare=False)
    from_profile: tuple[str, ...] = field(default=(), compare=False)

    @property
    def speed_value(self) -> float | None:
        return self.speed.value

    @property
    def speed_sigma(self) -> float | None:
        return self.speed.sigma

    def sensor(self, channel) -> ChannelSensor | None:
        """The sensor of ``channel`` (None for a channel the recording did not have when resolved)."""
        return next((s for s in self.sensors if s.channel == str(channel)), None)

    @property
    def sensors_by_channel(self) -> dict[str, ChannelSensor]:
        return {s.channel: s for s in self.sensors}

    def as_dict(self) -> dict:
        """The settings as plain numbers and words (what a test or a JSON output compares)."""
        return {
            "speed_m_s": self.speed.value,
            "speed_sigma_m_s": self.speed.sigma,
            "speed_source": self.speed.source,
            "speed_sigma_source": self.speed.sigma_source,
            "nominal_pitch_m": self.nominal_pitch,
            "teeth": self.teeth,
            "links_per_step": self.links_per_step,
            "n_links": self.n_links,
            "band_hz": None if self.band is None else list(self.band),
            "limits_percent": list(self.limits),
            "sensors": {s.channel: s.kind for s in self.sensors},
            "segment_s": None if self.segment is None else list(self.segment),
        }


def recording_chain(recording) -> tuple[int | None, int | None]:
    """``(sprocket teeth, links per step)`` a recording states (a vibkit simulation's ``sprocket_teeth`` and
    ``links_per_step``), None for each it does not state as a whole number of at least 1."""
    out = []
    for key in ("sprocket_teeth", "links_per_step"):
        try:
            v = int(getattr(recording, "attrs", {}).get(key))
        except (TypeError, ValueError):
            v = None
        out.append(v if v is not None and v >= 1 else None)
    return out[0], out[1]


def chain_numbers(*, teeth=None, links_per_step=None, profile=None, scene=None, recording=None) -> tuple[int, int]:
    """``(teeth, links per step)`` of a run: each as given, else the profile's, else the scene's, else the
    recording's (:func:`recording_chain`), else the defaults (:data:`DEFAULT_TEETH`, :data:`DEFAULT_LINKS_PER_STEP`)."""
    stated = recording_chain(recording) if recording is not None else (None, None)

    def first(given, of_profile, of_scene, of_file, default):
        for v in (given, of_profile, of_scene, of_file):
            if v is not None:
                return int(v)
        return default

    return (
        first(
            teeth,
            getattr(profile, "teeth", None),
            scene.sprocket.teeth if scene is not None else None,
            stated[0],
            DEFAULT_TEETH,
        ),
        first(
            links_per_step,
            getattr(profile, "links_per_step", None),
            scene.chain.links_per_step if scene is not None else None,
            stated[1],
            DEFAULT_LINKS_PER_STEP,
        ),
    )


def scene_is_unit(scene, profile) -> bool:
    """Whether ``scene`` simulates the profile's unit: the scene is the profile's (built from it), or its
    name or file name is the unit's identifier.  Without a profile no scene is a named unit's."""
    if scene is None or profile is None:
        return False
    unit = str(getattr(profile, "unit", "") or "").strip().lower()
    if not unit:
        return False
    if getattr(scene, "source", None) and str(scene.source) == str(getattr(profile, "source", "")):
        return True  # built from the profile
    names = {str(scene.name or "").strip().lower()}
    if getattr(scene, "source", None):
        names.add(os.path.splitext(os.path.basename(str(scene.source)))[0].lower())
    return unit in names


def resolve_n_links(given, profile=None, scene=None) -> tuple[int | None, str, list[str]]:
    """``(links in the chain, where from, notes)`` as :func:`resolve_settings` resolves them (see :func:`_n_links`)."""
    notes = []
    n, source = _n_links(given, profile, scene, notes)
    return n, source, notes


def _n_links(given, profile, scene, notes):
    """(links in the chain, where from): given, else the profile's ``chain.n_links``, else the scene's where it is
    the unit's (or there is no profile), else the number the profile's scene fills in from its geometry; a given
    number the profile's own ``chain.n_links`` contradicts is a :class:`SettingsError`."""
    own = getattr(profile, "n_links", None) if profile is not None else None
    if given and own and int(given) != int(own):
        raise SettingsError(
            f"--links {given} contradicts the escalator profile {profile.source} (chain.n_links = {own}): give "
            "one of them, or mend the profile",
            "n_links",
        )
    if given:
        return int(given), "given"
    if own:
        return int(own), f"{profile.source}: chain.n_links"
    if scene is not None and (profile is None or scene_is_unit(scene, profile)):
        return int(scene.chain.n_rollers), "the scene's chain"
    if profile is None:
        return None, ""
    try:  # a profile with its geometry instead: the number of links its scene fills in
        n = profile.scene("forward").chain.n_rollers
    except ValueError:
        return None, ""
    notes.append(
        f"{profile.source}: {n} links, filled in from its geometry (whole "
        f"{'pallets' if getattr(profile, 'is_walk', False) else 'steps'} that close the loop); give "
        "chain.n_links or --links N when you know the chain's count"
    )
    return int(n), f"{profile.source}: its geometry"


def resolve_settings(
    recording=None,
    *,
    speed=None,
    speed_sigma=None,
    nominal_pitch=None,
    teeth=None,
    links_per_step=None,
    n_links=None,
    band=None,
    limits=None,
    segment=None,
    profile=None,
    scene=None,
    frequency_only_band=False,
) -> RunSettings:
    """The one :class:`RunSettings` of a run: each setting as given, else the escalator ``profile``'s, else the
    ``scene``'s (a :class:`vibkit.model.scene.Scene` simulated beside the recording), else what ``recording``
    states, else the defaults of this module.

    Parameters
    ----------
    recording : xarray.Dataset, optional
        The recording analysed (as read; its speed, chain numbers and channels' sensors).
    speed, speed_sigma
        As :func:`vibkit.diagnose.speed.resolve_speed` takes them ([m/s]; the sigma also as ``"0.1%"``).
    nominal_pitch : float, optional
        [m]; else the profile's, else the pitch the scene's sprocket is cut for.
    teeth, links_per_step, n_links : int, optional
        Else the profile's, the scene's, the recording's (:func:`chain_numbers`, :func:`_n_links`).
    band : (float, float), optional
        [Hz]; else, with a profile and a speed, :data:`PROFILE_BAND_FACTORS` of its link pass; else with
        ``frequency_only_band`` and no speed :data:`FREQUENCY_ONLY_BAND_HZ`; else None.
    limits : (float, float, float), optional
        [%]; else :data:`DEFAULT_LIMITS_PERCENT`.
    segment : (float, float) or str, optional
        The part of the recording analysed [s] (``recording`` is that part already,
        :func:`vibkit.diagnose.segment.cut_recording`).

    Raises
    ------
    SettingsError
        A given number of links the profile contradicts.
    ValueError
        A speed that is not positive, a negative sigma, a segment that is not ``START:END``.
    """
    notes, taken = [], []
    n, n_source = _n_links(n_links, profile, scene, notes)  # first: a contradiction is the one line said
    sp = resolve_speed(speed, speed_sigma, profile=profile, recording=recording, scene=scene)
    if profile is not None and sp.value is not None and sp.source != "given":
        taken.append(f"speed {sp.text}")
    nominal, nominal_source = nominal_pitch, "given" if nominal_pitch is not None else ""
    if nominal is None and profile is not None and getattr(profile, "nominal_pitch", None):
        nominal, nominal_source = float(profile.nominal_pitch), f"{profile.source}: chain.nominal_pitch"
        taken.append(f"nominal pitch {1000 * nominal:g} mm")
    if nominal is None and scene is not None:  # the pitch the sprocket's teeth are cut for, not a worn chain's
        nominal, nominal_source = float(scene.sprocket.pitch), "the scene's sprocket"
    search, band_source = (tuple(band), "given") if band is not None else (None, "")
    if search is None and profile is not None and sp.value is not None:
        f = float(sp.value) / profile.nominal_pitch  # the profile's link pass (Profile.search_band's numbers)
        search = (PROFILE_BAND_FACTORS[0] * f, PROFILE_BAND_FACTORS[1] * f)
        band_source = f"{profile.source}: {PROFILE_BAND_FACTORS[0]:g}-{PROFILE_BAND_FACTORS[1]:g} x speed / pitch"
        taken.append(f"search band {fmt_band(search)} (0.8-1.25 x speed / nominal pitch)")
    if search is None and frequency_only_band and sp.value is None:
        search, band_source = FREQUENCY_ONLY_BAND_HZ, "no speed: the band of a step chain's link pass"
    if teeth is None and profile is not None:
        taken.append(f"{int(profile.teeth)} sprocket teeth")
    n_teeth, per_step = chain_numbers(
        teeth=teeth, links_per_step=links_per_step, profile=profile, scene=scene, recording=recording
    )
    seg = parse_segment(segment) if isinstance(segment, str) else segment
    sensors = ()
    if recording is not None:
        names = [str(v) for v in recording.data_vars if "time" in recording[v].dims]
        sensors = tuple(channel_sensor(recording, c, profile) for c in names)
    return RunSettings(
        speed=sp,
        nominal_pitch=None if nominal is None else float(nominal),
        nominal_pitch_source=nominal_source,
        teeth=n_teeth,
        links_per_step=per_step,
        n_links=n,
        n_links_source=n_source,
        band=None if search is None else (float(search[0]), float(search[1])),
        band_source=band_source,
        limits=tuple(float(v) for v in (limits if limits is not None else DEFAULT_LIMITS_PERCENT)),
        sensors=sensors,
        segment=None if seg is None else (float(seg[0]), float(seg[1])),
        notes=tuple(notes),
        from_profile=tuple(taken),
    )
