"""Escalator profiles: a small TOML file that describes the user's own escalator.

A profile names the unit (``[escalator]``), states its rated step speed (``[drive]``), its chain
(``[chain]``: the nominal pitch, links per step, the number of links) and, where the firm knows them,
its geometry (``[geometry]``: rise and incline, from which the loop follows), the tensioner's preload
(``[tensioner]``) and where the sensor sat (``[sensor]``, the default of every channel, and ``[sensors.NAME]``, the
sensor of the channel NAME where the unit's recordings have several). ``load_profile(path) -> Profile`` reads and
checks it; a wrong or missing key is a :class:`~vibkit.model.scene.SceneError` naming the file and the
key. Every key, with its unit, default, plausible range and meaning, is declared once below with the
scene schema's :func:`~vibkit.model.schema.key` (:func:`profile_table` renders them as a table).

A speed in a profile is the step (chain) speed on the straight, the speed a tachometer on a step
reads; nothing else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from .profile_scene import DEFAULT_INCLINE_DEG, profile_scene, scene_text
from .scene import SceneError, _check_scene_file, _section, toml_loads
from .schema import _fmt, _Section, key

__all__ = [
    "PROFILE_SECTIONS",
    "STANDARD_SPEED_TOLERANCE",
    "Profile",
    "Sensor",
    "load_profile",
    "parse_profile",
    "profile_fields",
    "profile_table",
]

#: EN 115-1 (safety of escalators and moving walks): at nominal frequency and voltage the no-load speed
#: may deviate from the nominal speed by at most +-5 %. A rated speed is known to no better than this.
STANDARD_SPEED_TOLERANCE = 0.05

#: where a sensor sits: the tension carriage (a displacement), a step, or a phone carried on a step
SENSOR_KINDS = ("tensioner", "step", "phone")
#: the kinds that ride a step (the link pass a step reads, not the chain's: ``vibkit pitch`` warns)
STEP_KINDS = ("step", "phone")
DIRECTIONS = ("up", "down")


@dataclass(frozen=True)
class EscalatorKeys(_Section):
    unit: str = key("", "the unit's identifier (as in the fleet catalogue), e.g. E07", types=(str,), required=True)
    site: str = key("", "where it stands, e.g. Leon, Plaza Mayor, east entrance", "", types=(str,))
    description: str = key("", "one line on the machine (make, year, use)", "", types=(str,))


@dataclass(frozen=True)
class DriveKeys(_Section):
    speed: float = key(
        "m/s",
        "rated step (chain) speed on the straight",
        required=True,
        range=(0.05, 1.0, "m/s (escalators run at 0.75 m/s at most, EN 115-1: a speed in km/h?)"),
    )
    speed_uncertainty: float = key(
        "m/s",
        "stated 1-sigma of the speed (a measurement); not set: the standard's tolerance, +-5 % uniform",
        range=(0.0, 0.5, "m/s"),
    )
    teeth: int = key("", "teeth of the step-chain sprocket", 28, types=(int,), range=(8, 60, "teeth"))
    direction: str = key("", '"up" or "down": the way the steps travel on the incline', "up", types=(str,))
    no_load_power: float = key(
        "W",
        "power the drive gives the step chain at the rated speed with no passengers (the motor's no-load input less "
        "its and the gearbox's losses): the scene drives its chain against that running resistance; not set: a typical "
        "figure, 88.9 N per metre of loop x loop x speed (vibkit.model.profile_scene); 0: none, the chain coasts",
        range=(0.0, 1e5, "W (a no-load drive power in kW?)"),
    )


@dataclass(frozen=True)
class ChainKeys(_Section):
    nominal_pitch: float = key(
        "m", "nominal link pitch of the step chain (new)", required=True, range=(0.05, 0.25, "m (step chains)")
    )
    links_per_step: int = key("", "links (rollers) per step: 3 or 4", 3, types=(int,), range=(3, 4, "links"))
    n_links: int = key(
        "",
        "links of one chain strand (the closed loop); not set: from geometry.rise and geometry.incline_deg",
        types=(int,),
        range=(20, 5000, "links"),
    )
    roller_radius: float = key(
        "m", "roller radius; not set: scaled from the reference chain with the pitch", range=(0.005, 0.1, "m")
    )


@dataclass(frozen=True)
class GeometryKeys(_Section):
    rise: float = key(
        "m",
        "an escalator's height between the landings; with incline_deg gives the loop if n_links is not set",
        range=(0.5, 30, "m"),
    )
    length: float = key(
        "m",
        "a moving walk's length between the heads' axles, in plan; with incline_deg gives the loop",
        range=(2.0, 400.0, "m"),
    )
    incline_deg: float = key(
        "deg",
        "angle of the incline: 27.3 to 35 for an escalator (with rise), 0 to 12 for a moving walk (with length)",
        range=(0.0, 45.0, "deg"),
    )


#: the escalator's plausible incline [deg] (EN 115-1: 30 deg, 35 deg up to a 6 m rise; 27.3 deg is common)
ESCALATOR_INCLINE = (5.0, 45.0)
#: a moving walk's incline [deg]: EN 115-1 allows 12 deg at most
WALK_INCLINE = (0.0, 12.0)
_GEOMETRY_RANGE = {f.name: f.metadata["range"] for f in GeometryKeys.fields()}
#: what each kind of unit is described by, for the one-line refusal of a profile that describes neither
KINDS_TEXT = (
    f"an escalator is described by 'geometry.rise' ({_GEOMETRY_RANGE['rise'][0]:g} to "
    f"{_GEOMETRY_RANGE['rise'][1]:g} m) and 'geometry.incline_deg' ({ESCALATOR_INCLINE[0]:g} to "
    f"{ESCALATOR_INCLINE[1]:g} deg), a moving walk by 'geometry.length' (m, between the heads) and "
    f"'geometry.incline_deg' ({WALK_INCLINE[0]:g} to {WALK_INCLINE[1]:g} deg, EN 115-1)"
)


def _check_geometry(src, g: dict, c: dict) -> None:
    """The geometry keys together: an escalator (rise and incline) or a moving walk (length and incline), or
    neither when the chain's ``n_links`` is given alone; anything else is refused in one line naming the keys."""
    rise, length, incline = g.get("rise"), g.get("length"), g.get("incline_deg")
    if not g:
        if "n_links" not in c:
            raise SceneError(
                f"{src}: missing value 'chain.n_links' or the geometry, from which the loop follows: {KINDS_TEXT}"
            )
        return
    given = ", ".join(f"'geometry.{k}' = {v!r}" for k, v in g.items())
    if rise is not None and length is not None:
        raise SceneError(
            f"{src}: {given}: a unit has a rise (escalator) or a length (moving walk), not both: {KINDS_TEXT}"
        )
    if incline is None and rise is not None and "n_links" in c:
        incline = DEFAULT_INCLINE_DEG  # (as the scene fills it in, said in its comments)
    if incline is None:
        which = "rise" if rise is not None else "length"
        raise SceneError(
            f"{src}: missing value 'geometry.incline_deg' (the incline, with 'geometry.{which}'): {KINDS_TEXT}"
        )
    if length is not None:
        lo, hi, unit = _GEOMETRY_RANGE["length"]
        if WALK_INCLINE[0] <= incline <= WALK_INCLINE[1] and lo <= length <= hi:
            return
        if not lo <= length <= hi:
            raise SceneError(
                f"{src}: 'geometry.length' = {length!r} is outside the plausible range [{lo:g}, {hi:g}] {unit} "
                "(a moving walk's length between the heads)"
            )
        raise SceneError(
            f"{src}: {given}: a moving walk inclines {WALK_INCLINE[1]:g} deg at most (EN 115-1); a steeper unit is an "
            f"escalator: {KINDS_TEXT}"
        )
    if rise is not None:
        lo, hi, _ = _GEOMETRY_RANGE["rise"]
        if lo <= rise <= hi and ESCALATOR_INCLINE[0] <= incline <= ESCALATOR_INCLINE[1]:
            return
        mm = " (millimetres typed as metres?)" if lo <= rise / 1000 <= hi else ""
        raise SceneError(f"{src}: {given} describes neither an escalator nor a moving walk{mm}: {KINDS_TEXT}")
    raise SceneError(f"{src}: {given} alone describes neither an escalator nor a moving walk: {KINDS_TEXT}")


@dataclass(frozen=True)
class TensionerKeys(_Section):
    preload: float = key(
        "N", "tensioner spring preload; not set: chosen so that no link goes into compression", range=(0.0, 1e6, "N")
    )


@dataclass(frozen=True)
class SensorKeys(_Section):
    kind: str = key(
        "",
        '"tensioner" (displacement of the tension carriage), "step" (on a step) or "phone" (a phone on a step)',
        types=(str,),
    )
    step: int = key("", "1-based step carrying the sensor (kind = step)", types=(int,), range=(1, 2000, ""))


#: section name -> its class, in the order of a profile file
PROFILE_SECTIONS = {
    "escalator": EscalatorKeys,
    "drive": DriveKeys,
    "chain": ChainKeys,
    "geometry": GeometryKeys,
    "tensioner": TensionerKeys,
    "sensor": SensorKeys,
}


def profile_fields():
    """(section, field) for every key of a profile, in the order of a profile file."""
    return [(name, f) for name, cls in PROFILE_SECTIONS.items() for f in cls.fields()]


def profile_table() -> str:
    """The profile's keys as a Markdown table: section, key, unit, default, plausible range, meaning."""
    rows = ["| section | key | unit | default | range | meaning |", "|---|---|---|---|---|---|"]
    for sec, f in profile_fields():
        m = f.metadata
        default = "required" if m["required"] else _fmt(f.default)
        rg = m["range"]
        rng = f"[{rg[0]:g}, {rg[1]:g}]" if rg else ""
        rows.append(f"| [{sec}] | {f.name} | {m['unit']} | {default} | {rng} | {m['doc']} |")
    return "\n".join(rows) + "\n"


@dataclass(frozen=True)
class Sensor:
    """Where a sensor of the recordings sat: ``kind`` "tensioner", "step" or "phone"; ``step`` (1-based) on a step."""

    kind: str
    step: int | None = None


@dataclass(frozen=True, kw_only=True)
class Profile:
    """A validated escalator profile (SI units; see the module doc and :func:`profile_table`).

    ``n_links`` is None when the profile gives the geometry instead: ``rise`` and ``incline_deg`` (an
    escalator) or ``length`` and ``incline_deg`` (a moving walk, :attr:`is_walk`).
    """

    unit: str
    speed: float
    nominal_pitch: float
    site: str = ""
    description: str = ""
    speed_uncertainty: float | None = None
    links_per_step: int = 3
    n_links: int | None = None
    rise: float | None = None
    length: float | None = None
    incline_deg: float | None = None
    teeth: int = 28
    direction: str = "up"
    no_load_power: float | None = None
    roller_radius: float | None = None
    tensioner_preload: float | None = None
    sensor: Sensor | None = None
    #: channel name -> its sensor (``[sensors.NAME]``); a channel not named here has :attr:`sensor`
    sensors: dict[str, Sensor] = field(default_factory=dict)
    source: str = "<string>"

    def search_band(self, speed) -> tuple[float, float]:
        """The link-pass search band at ``speed`` [m/s]: 0.8 to 1.25 times speed / nominal pitch, wider than any
        chain wears, narrow enough to keep the neighbouring periodicities out. [Hz]"""
        f = float(speed) / self.nominal_pitch
        return (0.8 * f, 1.25 * f)

    @property
    def speed_sigma(self) -> tuple[float, str]:
        """(1-sigma of the speed [m/s], where it comes from).

        The stated ``drive.speed_uncertainty`` when the profile gives one; else the tolerance of the
        escalator standard: EN 115-1 allows the no-load speed to deviate by +-5 % from the nominal speed
        at nominal frequency and voltage; taken as a uniform band, its standard deviation is
        5 % / sqrt(3) = 2.9 % of the speed. :attr:`speed_sigma_from_standard` says which.
        """
        if self.speed_uncertainty is not None:
            return self.speed_uncertainty, f"{self.source}: drive.speed_uncertainty"
        sigma = STANDARD_SPEED_TOLERANCE / math.sqrt(3.0) * self.speed
        return sigma, (
            f"not stated in {self.source}: the rated speed's tolerance of EN 115-1 "
            f"(+-{100 * STANDARD_SPEED_TOLERANCE:g} % uniform, sigma {100 * STANDARD_SPEED_TOLERANCE / math.sqrt(3):.1f} %)"
        )

    @property
    def speed_sigma_from_standard(self) -> bool:
        """True when :attr:`speed_sigma` is the standard's tolerance, not a measurement the profile states."""
        return self.speed_uncertainty is None

    @property
    def is_walk(self) -> bool:
        """Whether the unit is a moving walk (the profile gives ``geometry.length``), not an escalator."""
        return self.length is not None

    @property
    def kind(self) -> str:
        """``"moving walk"`` or ``"escalator"``, as a page names the unit."""
        return "moving walk" if self.is_walk else "escalator"

    @property
    def geometry_given(self) -> bool:
        """Whether the profile states the unit's geometry (rise or length, with the incline); without it the
        scene is an escalator of the common 30 deg incline whose rise follows from ``chain.n_links``."""
        return self.rise is not None or self.length is not None

    @property
    def name(self) -> str:
        """The unit and its site, for a title: ``E07 (Leon, Plaza Mayor)``."""
        return f"{self.unit} ({self.site})" if self.site else self.unit

    @property
    def on_step(self) -> bool | None:
        """Whether the recordings' sensor rides a step (``sensor.kind = "step"``); None when the profile does not
        say where it sat."""
        return None if self.sensor is None else self.sensor.kind in STEP_KINDS

    @property
    def set_speed(self) -> float:
        """The chain speed a simulation of this escalator sets, signed: the rated speed, negative when the steps
        travel down (:attr:`direction`). [m/s]"""
        return -self.speed if self.direction == "down" else self.speed

    @property
    def link_pass_frequency_hz(self) -> float:
        """The link-pass frequency of a new chain at the rated speed, speed / pitch. [Hz]"""
        return self.speed / self.nominal_pitch

    def scene(self, analysis: str = "forward", duration: float | None = None):
        """The scene of this escalator (a :class:`~vibkit.model.scene.Scene`, in memory): what the profile
        says, the rest from standard step-chain proportions (:mod:`vibkit.model.profile_scene`); a
        geometry that cannot run is a SceneError naming the profile key to change."""
        return profile_scene(self, analysis, duration)

    def scene_text(self, analysis: str = "forward", duration: float | None = None) -> str:
        """The TOML text of :meth:`scene`, with comments saying where each value came from."""
        return scene_text(self, analysis, duration)

    def band(self, low=0.8, high=1.25) -> tuple[float, float]:
        """A search band of the link pass around :attr:`link_pass_frequency_hz` [Hz]: a worn chain
        (longer pitch) and a speed off its rating both stay inside."""
        f = self.link_pass_frequency_hz
        return (low * f, high * f)


def parse_profile(text: str, source: str = "<string>") -> Profile:
    """Validate a profile given as TOML text (see :func:`load_profile`)."""
    src = source
    if text.startswith("\ufeff"):
        text = text[1:]
    data = toml_loads(text, src, "profile")
    for name in data:
        if name not in PROFILE_SECTIONS and name != "sensors":
            raise SceneError(f"{src}: unknown section [{name}] (known: {', '.join(PROFILE_SECTIONS)}, sensors.NAME)")
    sec = {}
    for name, cls in PROFILE_SECTIONS.items():
        schema = {
            f.name: (f.metadata["types"][0] if len(f.metadata["types"]) == 1 else f.metadata["types"])
            for f in cls.fields()
        }
        sec[name] = _section(src, data, name, schema)
        for f in cls.fields():
            where = f"{name}.{f.name}"
            if f.metadata["required"] and f.name not in sec[name]:
                raise SceneError(f"{src}: missing value '{where}' ({f.metadata['doc']})")
            v = sec[name].get(f.name)
            rg = f.metadata["range"]
            if rg and name != "geometry" and isinstance(v, (int, float)) and not rg[0] <= v <= rg[1]:
                metres = f.metadata["unit"] == "m" and rg[0] <= v / 1000 <= rg[1] and rg[0] > 0
                hint = f"; did you mean {v / 1000:.5g} m? (millimetres typed as metres)" if metres else ""
                raise SceneError(
                    f"{src}: '{where}' = {v!r} is outside the plausible range [{rg[0]:g}, {rg[1]:g}] {rg[2]}{hint}"
                )
    e, d, c, g, t, s = (sec[n] for n in PROFILE_SECTIONS)
    _check_geometry(src, g, c)
    if not e["unit"].strip():
        raise SceneError(f"{src}: 'escalator.unit' must not be empty (the unit's identifier, e.g. E07)")
    if d.get("direction", "up") not in DIRECTIONS:
        raise SceneError(f"{src}: 'drive.direction' must be one of {', '.join(DIRECTIONS)}, got {d.get('direction')!r}")
    sensor = _sensor(src, "sensor", s) if s else None
    return _profile(src, source, e, d, c, g, t, sensor, _channel_sensors(src, data.get("sensors", {})))


def _sensor(src, where, s) -> Sensor:
    """One sensor's keys (``[sensor]`` or ``[sensors.NAME]``, named ``where``) checked."""
    if s.get("kind") not in SENSOR_KINDS:
        raise SceneError(f"{src}: '{where}.kind' must be one of {', '.join(SENSOR_KINDS)}, got {s.get('kind')!r}")
    if s["kind"] == "step" and "step" not in s:
        raise SceneError(f"{src}: missing value '{where}.step' (the 1-based step carrying the sensor)")
    if s["kind"] == "tensioner" and "step" in s:
        raise SceneError(f"{src}: '{where}.step' has no meaning with {where}.kind = \"tensioner\"")
    return Sensor(kind=s["kind"], step=s.get("step"))


def _channel_sensors(src, raw) -> dict[str, Sensor]:
    """``[sensors.NAME]`` tables: channel NAME -> its sensor, each checked as ``[sensor]`` is."""
    if not isinstance(raw, dict):
        raise SceneError(f'{src}: [sensors] must hold one table per channel, e.g. [sensors.acc_z] kind = "phone"')
    schema = {
        f.name: (f.metadata["types"][0] if len(f.metadata["types"]) == 1 else f.metadata["types"])
        for f in SensorKeys.fields()
    }
    out = {}
    for name, table in raw.items():
        where = f"sensors.{name}"
        if not isinstance(table, dict):
            raise SceneError(f"{src}: '{where}' must be a table naming the channel's sensor (kind = ...)")
        checked = _section(src, {where: table}, where, schema)
        rg = SensorKeys.fields()[1].metadata["range"]
        if "step" in checked and not rg[0] <= checked["step"] <= rg[1]:
            raise SceneError(f"{src}: '{where}.step' = {checked['step']!r} is outside [{rg[0]:g}, {rg[1]:g}]")
        out[str(name)] = _sensor(src, where, checked)
    return out


def _profile(src, source, e, d, c, g, t, sensor, sensors) -> Profile:
    return Profile(
        unit=e["unit"],
        site=e.get("site", ""),
        description=e.get("description", ""),
        speed=d["speed"],
        speed_uncertainty=d.get("speed_uncertainty"),
        teeth=d.get("teeth", DriveKeys.teeth),
        direction=d.get("direction", DriveKeys.direction),
        no_load_power=d.get("no_load_power"),
        nominal_pitch=c["nominal_pitch"],
        links_per_step=c.get("links_per_step", ChainKeys.links_per_step),
        n_links=c.get("n_links"),
        roller_radius=c.get("roller_radius"),
        rise=g.get("rise"),
        length=g.get("length"),
        incline_deg=g.get("incline_deg"),
        tensioner_preload=t.get("preload"),
        sensor=sensor,
        sensors=sensors,
        source=source,
    )


def load_profile(path) -> Profile:
    """Read and validate an escalator profile (TOML).

    Raises
    ------
    SceneError
        The file is missing, not TOML, or has an unknown key, a missing value or an implausible
        number; the one-line message names the file and the key.
    """
    p = Path(path)
    _check_scene_file(p, "profile")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{p}: cannot read profile file ({exc})") from None
    return parse_profile(text, str(p))
