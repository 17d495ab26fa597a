"""Scenes: TOML files that say which escalator, which analysis, which effects and which outputs.

``load_scene(path) -> Scene`` reads and validates a scene once, at the boundary; an unknown key, a
missing value or a non-physical number is a :class:`SceneError` that names the file and the key.
A scene asks only for the effects and outputs it needs; :func:`vibkit.simulate` assembles,
evaluates and stores only those.

The sections are ``[scene]``, ``[guide]``, ``[chain]``, ``[sprocket]``, the analysis's own
(``[kinematics]``, ``[motion]`` or ``[run]``), ``[solver]`` (forward), ``[effects.*]`` and ``[outputs]``
(see ``sim/*.toml`` for complete examples). Every key, with its unit, default, plausible range and
meaning, is declared once in :mod:`vibkit.model.schema` (:func:`~vibkit.model.schema.schema_table`
renders them as a table); this module reads the TOML, checks it against the schema and the rules
between keys (the chain closes on the guide, a tooth fits a link, ...), and builds the typed scene.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..runtime.budget import parse_bytes
from ..scenes import find
from .chain_keys import by_roller, check_flat_speed, check_seat, worn_links
from .params import TRAVEL, ChainParams, GuideParams, SprocketParams
from .scene_checks import (
    MAX_TOML_DEPTH,  # noqa: F401 - public through the scene loader
    _check_ranges,
    _check_sprocket_geometry,
    _reduce_start,
    _validate_passenger_numbers,
    check_chain_first,
    check_sections_belong,
    toml_loads,
)
from .schema import (
    ANALYSIS_EFFECTS,
    EFFECT_OPTIONS,
    EFFECTS,
    OUTPUTS,
    RANGES,
    SECTION_CLASSES,
    SECTIONS,
    ChainSection,
    GuideSection,
    KinematicsSection,
    MotionSection,
    OutputsSection,
    RunSection,
    SceneError,
    SolverSection,
    SprocketSection,
    check_geometry_range,
)

__all__ = ["Scene", "SceneError", "load_scene", "parse_scene", "EFFECTS", "OUTPUTS", "RANGES", "SECTIONS"]

ANALYSES = ("kinematics", "inverse", "forward")

#: the integrators of :mod:`vibkit.analyses.integrate` (kept equal to ``integrate.METHODS`` by a test; listed
#: here so that loading a scene does not import the compiled kernels)
SOLVER_METHODS = ("dopri5", "rk45", "dop853", "bdf", "radau", "lsoda", "cvode-bdf", "cvode-adams")

#: a scene is a small text file; anything larger is not one
MAX_SCENE_BYTES = 1 << 20

# how the forward dynamics gets the chain's configuration: read from the table over one pitch, or
# solved at every evaluation (vibkit.model.pitch_table)
CLOSURES = ("table", "exact", "runs")

# places of the guide where passengers board and alight (vibkit.model.escalator.EscalatorModel.place)
PLACES = ("lower_landing", "upper_landing")


@dataclass(frozen=True, kw_only=True)
class Scene:
    """A validated scene.

    Attributes
    ----------
    name, analysis, description : str
    guide, chain, sprocket : parameter dataclasses (SI)
    sections : dict
        The keys the file gives in the analysis-specific sections (``kinematics``, ``motion``, ``run``,
        ``solver``); read them typed, with the schema's defaults, as :attr:`kinematics`,
        :attr:`motion`, :attr:`run` and :attr:`solver` (:mod:`vibkit.model.schema`).
    effects : dict
        Effect name -> typed options (:data:`vibkit.model.schema.EFFECT_OPTIONS`), only the effects
        the scene asks for.
    outputs : dict
        ``variables`` (tuple of names), ``rollers`` (tuple of 1-based roller numbers),
        ``step_accelerometer`` (1-based step number or None).
    source : str
        The file the scene came from (or "<string>").
    text : str
        The TOML text, stored in results for provenance.
    defaults : tuple of str
        The dotted keys (of the sections and effects the scene uses) that took the schema's
        default because the file does not give them; results record them in ``attrs["scene_defaults"]``.
    """

    name: str
    analysis: str
    description: str
    guide: GuideParams
    chain: ChainParams
    sprocket: SprocketParams
    sections: dict = field(default_factory=dict)
    effects: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)
    source: str = "<string>"
    text: str = ""
    defaults: tuple = ()

    def section(self, name: str) -> dict:
        """The keys the file gives in section ``name`` (untyped; the analyses read the typed sections)."""
        return self.sections.get(name, {})

    @property
    def kinematics(self) -> KinematicsSection:
        return KinematicsSection.from_mapping(self.section("kinematics"))

    @property
    def motion(self) -> MotionSection:
        return MotionSection.from_mapping(self.section("motion"))

    @property
    def run(self) -> RunSection:
        return RunSection.from_mapping(self.section("run"))

    @property
    def solver(self) -> SolverSection:
        return SolverSection.from_mapping(self.section("solver"))

    def with_solver(self, **keys) -> Scene:
        """This scene with the ``[solver]`` keys ``keys`` set (as if the file gave them)."""
        sections = dict(self.sections, solver={**self.section("solver"), **keys})
        return dataclasses.replace(self, sections=sections)


def _err(src, key, msg):
    return SceneError(f"{src}: [{key}] {msg}" if not key.startswith("[") else f"{src}: {key} {msg}")


def _check_type(src, where, value, typ):
    types = typ if isinstance(typ, tuple) else (typ,)
    if float in types and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if bool not in types and isinstance(value, bool):
        raise SceneError(f"{src}: {where} expected {'/'.join(t.__name__ for t in types)}, got a boolean")
    if not isinstance(value, types):
        raise SceneError(
            f"{src}: {where} expected {'/'.join(t.__name__ for t in types)}, got {type(value).__name__} {value!r}"
        )
    if isinstance(value, float) and not math.isfinite(value):
        raise SceneError(f"{src}: {where} must be finite, got {value!r}")
    return value


def _section(src, data, name, schema):
    raw = data.get(name, {})
    if not isinstance(raw, dict):
        raise SceneError(f"{src}: [{name}] must be a table")
    out = {}
    for key, value in raw.items():
        if key not in schema:
            known = ", ".join(sorted(schema))
            raise SceneError(f"{src}: unknown key '{name}.{key}' (known keys of [{name}]: {known})")
        out[key] = _check_type(src, f"'{name}.{key}'", value, schema[key])
    return out


def _positive(src, where, value):
    if not value > 0:
        raise SceneError(f"{src}: '{where}' must be positive, got {value!r}")


def parse_scene(text: str, source: str = "<string>") -> Scene:
    """Validate a scene given as TOML text (see :func:`load_scene`)."""
    src = source
    if text.startswith("\ufeff"):  # a UTF-8 byte-order mark (Windows editors write one)
        text = text[1:]
    data = toml_loads(text, src)
    allowed = set(SECTIONS) | {"effects"}
    for key in data:
        if key not in allowed:
            raise SceneError(f"{src}: unknown section [{key}] (known: {', '.join(sorted(allowed))})")
    sec = {name: _section(src, data, name, schema) for name, schema in SECTIONS.items()}

    scene_sec = sec["scene"]
    if "analysis" not in scene_sec:
        raise SceneError(f"{src}: missing value 'scene.analysis' (one of {', '.join(ANALYSES)})")
    analysis = scene_sec["analysis"]
    if analysis not in ANALYSES:
        raise SceneError(f"{src}: 'scene.analysis' must be one of {', '.join(ANALYSES)}, got {analysis!r}")

    _escalator_stated(src, data)
    check_chain_first(src, sec)
    guide, chain, sprocket = _parameters(src, sec)

    raw_effects = data.get("effects", {})
    effects = _effects(src, raw_effects, analysis)
    outputs = _outputs(src, sec["outputs"], analysis, chain)
    _analysis_sections(src, sec, analysis)
    _validate_passenger_numbers(src, effects.get("passengers"), chain)
    _check_ranges(src, sec, effects)
    _check_sprocket_geometry(src, sec["sprocket"], sprocket, chain)
    check_flat_speed(src, chain, guide, analysis, effects, sec)
    _reduce_start(src, sec, analysis, guide)
    return Scene(
        defaults=_defaults(sec, raw_effects, effects, analysis),
        name=scene_sec.get("name", Path(source).stem),
        analysis=analysis,
        description=scene_sec.get("description", ""),
        guide=guide,
        chain=chain,
        sprocket=sprocket,
        sections={k: sec[k] for k in ("kinematics", "motion", "run", "solver")},
        effects=effects,
        outputs=outputs,
        source=source,
        text=text,
    )


#: the sections that describe the escalator: a scene states them (the study's values are never filled in)
ESCALATOR_SECTIONS = ("guide", "chain", "sprocket")


def _escalator_stated(src, data):
    """Refuse a scene that leaves out part of the escalator, naming every missing section and key at once."""
    missing_sections, missing_keys = [], []
    for name in ESCALATOR_SECTIONS:
        required = [f.name for f in SECTION_CLASSES[name].fields() if f.metadata["required"]]
        if name not in data:
            missing_sections.append(f"[{name}]")
        else:
            missing_keys += [f"'{name}.{k}'" for k in required if k not in data[name]]
    if not (missing_sections or missing_keys):
        return
    parts = []
    if missing_sections:
        parts.append(f"missing section{'s' if len(missing_sections) > 1 else ''} {', '.join(missing_sections)}")
    if missing_keys:
        parts.append(f"missing value{'s' if len(missing_keys) > 1 else ''} {', '.join(missing_keys)}")
    raise SceneError(
        f"{src}: {'; '.join(parts)}: a scene states the escalator it describes (guide geometry, link pitch, "
        "sprocket); copy them from a scene in sim/ and set your escalator's values"
    )


def _parameters(src, sec):
    # sprocket
    s = sec["sprocket"]
    for key in ("base_width", "tip_width", "tooth_height", "mass", "inertia"):
        if key in s:
            _positive(src, f"sprocket.{key}", s[key])
            check_geometry_range(src, f"sprocket.{key}", s[key])
    if "teeth" in s and s["teeth"] < 3:
        raise SceneError(f"{src}: 'sprocket.teeth' must be an integer >= 3, got {s['teeth']!r}")
    ts = SprocketSection.from_mapping(s)
    # chain
    c = sec["chain"]
    for key in ("link_pitch", "roller_radius", "roller_mass"):
        if key in c:
            _positive(src, f"chain.{key}", c[key])
            check_geometry_range(src, f"chain.{key}", c[key])
    tc = ChainSection.from_mapping(c)
    nominal = tc.link_pitch
    if "pitch" in s:
        _positive(src, "sprocket.pitch", s["pitch"])
        check_geometry_range(src, "sprocket.pitch", s["pitch"])
    sprocket = SprocketParams(
        **{k: getattr(ts, k) for k in ("teeth", "base_width", "tip_width", "tooth_height", "mass", "inertia")},
        pitch=ts.pitch if ts.pitch is not None else nominal,
    )
    elongation = tc.elongation_percent
    lo, hi, note = RANGES["chain.elongation_percent"]
    if not lo <= elongation <= hi:
        raise SceneError(
            f"{src}: 'chain.elongation_percent' = {elongation!r} is outside the plausible range [{lo:g}, {hi:g}] {note}"
        )
    pitch = nominal * (1.0 + elongation / 100.0)  # the worn chain's pitch, on teeth cut for the nominal one
    # guide
    g = sec["guide"]
    for key in ("tensioner_length", "lower_landing", "upper_landing", "transition_radius", "incline_length"):
        if key in g:
            _positive(src, f"guide.{key}", g[key])
            check_geometry_range(src, f"guide.{key}", g[key])
    tg = GuideSection.from_mapping(g)
    head = tg.head_radius
    if isinstance(head, str):
        if head != "sprocket":
            raise SceneError(f"{src}: 'guide.head_radius' must be a length [m] or \"sprocket\", got {head!r}")
        # where rollers of the chain's pitch seat on the teeth: one tooth pitch apart on this circle
        head = sprocket.pitch_radius(pitch)
        fitted = sprocket.pitch_radius(nominal)  # the head radius of the chain when it was new
    else:
        _positive(src, "guide.head_radius", head)
        check_geometry_range(src, "guide.head_radius", head)
        fitted = head
    angle = tg.incline_angle_deg
    if not 0 <= angle < 90:
        raise SceneError(
            f"{src}: 'guide.incline_angle_deg' must be in [0, 90) deg (0: a level moving walk), got {angle!r}"
        )
    guide_keys = dict(
        tensioner_length=tg.tensioner_length,
        lower_landing=tg.lower_landing,
        upper_landing=tg.upper_landing,
        transition_radius=tg.transition_radius,
        incline_angle=math.radians(angle),
        incline_length=tg.incline_length,
    )
    guide = GuideParams(**guide_keys, head_radius=head)
    n = tc.n_rollers
    filled = isinstance(n, str) and n == "fill"
    if isinstance(n, str):
        if n != "fill":
            raise SceneError(f"{src}: 'chain.n_rollers' must be an integer or \"fill\", got {n!r}")
        # as many links as fitted the guide when the chain was new (an elongated chain keeps its links)
        n = int(math.floor(GuideParams(**guide_keys, head_radius=fitted).perimeter / nominal))
    if n < 3:
        raise SceneError(f"{src}: 'chain.n_rollers' must be an integer >= 3, got {n!r}")
    worn = worn_links(src, c, n, nominal)
    radii = by_roller(src, c, "roller_radius_by_roller", n, "radius", "m")
    for roller, r in radii:
        if not r < 0.5 * nominal:
            raise SceneError(
                f"{src}: 'chain.roller_radius_by_roller': radius {r:g} m of roller {roller} must be less than half "
                f"the link pitch ({0.5 * nominal:g} m)"
            )
    flats = by_roller(src, c, "roller_flat_by_roller", n, "flat length", "m")
    radius_of = dict(radii)
    for roller, d in flats:
        r = radius_of.get(roller, tc.roller_radius)
        if not d < r:
            raise SceneError(
                f"{src}: 'chain.roller_flat_by_roller': the flat of roller {roller} ({d:g} m) must be shorter than "
                f"the roller's radius ({r:g} m); a flat that long is a broken roller"
            )
    if tc.links_per_step not in (3, 4):
        raise SceneError(f"{src}: 'chain.links_per_step' must be 3 or 4, got {tc.links_per_step!r}")
    chain = ChainParams(
        link_pitch=pitch,
        roller_radius=tc.roller_radius,
        roller_mass=tc.roller_mass,
        n_rollers=n,
        worn_links=worn,
        roller_masses=by_roller(src, c, "roller_mass_by_roller", n, "mass", "kg"),
        roller_radii=radii,
        roller_flats=flats,
        links_per_step=tc.links_per_step,
    )
    check_seat(src, guide, sprocket, chain)
    # the chain must close within the tensioner travel: P0 - 2 delta ~ sum of pitches, |delta| < travel
    slack = (guide.perimeter - float(chain.pitches().sum())) / 2.0
    travel = TRAVEL * guide.tensioner_length
    if not -travel < slack < travel:
        # name the key the user set: the links' count, or (with the count filled for the new chain) their pitch
        elongation = c.get("elongation_percent")
        if filled and elongation:
            what = (
                f"'chain.elongation_percent' = {elongation!r} (links of {pitch:.6g} m; 'chain.n_rollers' = \"fill\": "
                f"the {n} links of the new chain)"
            )
        elif filled:
            what = f"'chain.link_pitch' = {pitch:.6g} m ('chain.n_rollers' = \"fill\": {n} links)"
        else:
            what = f"'chain.n_rollers' = {n} links of {pitch:.6g} m"
        raise SceneError(
            f"{src}: {what} cannot close on a guide of perimeter {guide.perimeter:.6g} m: the tensioner would need "
            f"delta = {slack:.4g} m, outside its travel (-{travel:.4g}, {travel:.4g}) m"
        )
    return guide, chain, sprocket


def _effects(src, raw, analysis):
    if not isinstance(raw, dict):
        raise SceneError(f"{src}: [effects] must be a table")
    effects = {}
    for name, opts in raw.items():
        if name not in EFFECTS:
            raise SceneError(f"{src}: unknown effect 'effects.{name}' (known effects: {', '.join(EFFECTS)})")
        if isinstance(opts, bool):
            opts = {} if opts else None
        if opts is None:
            continue
        if not isinstance(opts, dict):
            raise SceneError(f"{src}: 'effects.{name}' must be true/false or a table of options")
        checked = {}
        for key, value in opts.items():
            if key not in EFFECTS[name]:
                raise SceneError(f"{src}: unknown key 'effects.{name}.{key}' (known: {', '.join(EFFECTS[name])})")
            checked[key] = _check_type(src, f"'effects.{name}.{key}'", value, EFFECTS[name][key])
        if checked.get("enabled", True) is False:
            continue
        effects[name] = checked
    if analysis == "kinematics" and effects:
        raise SceneError(f"{src}: [effects] have no meaning in a kinematics scene (got {', '.join(effects)})")
    allowed = ANALYSIS_EFFECTS[analysis]
    if analysis != "kinematics":
        extra = set(effects) - allowed
        if extra:
            raise SceneError(
                f"{src}: effect(s) {', '.join(sorted(extra))} not available in an {analysis} scene "
                f"(available: {', '.join(sorted(allowed))})"
            )
    _validate_effects(src, effects)
    return effects


def _validate_effects(src, eff):
    """Check the given options of each effect and replace them by typed options (schema defaults)."""
    if "contact" in eff:
        if "stiffness" not in eff["contact"]:
            raise SceneError(f"{src}: missing value 'effects.contact.stiffness' [N/m^exponent]")
    if "motor" in eff:
        for key in ("kp", "speed"):
            if key not in eff["motor"]:
                raise SceneError(f"{src}: missing value 'effects.motor.{key}'")
    if "rolling_resistance" in eff:
        if "coefficient" not in eff["rolling_resistance"]:
            raise SceneError(f"{src}: missing value 'effects.rolling_resistance.coefficient'")
    if "passengers" in eff:
        for key in ("mass", "step"):
            if key not in eff["passengers"]:
                raise SceneError(f"{src}: missing value 'effects.passengers.{key}' (a list, one entry per passenger)")
    for name in eff:
        eff[name] = EFFECT_OPTIONS[name].from_mapping(eff[name])
    if "contact" in eff:
        o = eff["contact"]
        _positive(src, "effects.contact.stiffness", o.stiffness)
        _positive(src, "effects.contact.exponent", o.exponent)
        if o.damping < 0:
            raise SceneError(f"{src}: 'effects.contact.damping' must be >= 0 [s/m], got {o.damping!r}")
    if "motor" in eff:
        o = eff["motor"]
        if o.ki < 0:
            raise SceneError(f"{src}: 'effects.motor.ki' must be >= 0 [N m], got {o.ki!r}")
        if not (o.kp == 0 and o.ki > 0):  # an integral controller alone may have kp = 0
            try:
                _positive(src, "effects.motor.kp", o.kp)
            except SceneError:
                raise SceneError(
                    f"{src}: 'effects.motor.kp' must be positive, or 0 with effects.motor.ki > 0, got {o.kp!r}"
                ) from None
        if o.torque_limit != math.inf:
            _positive(src, "effects.motor.torque_limit", o.torque_limit)
        if o.initial_torque != 0 and not (o.ki > 0 and o.speed != 0):
            raise SceneError(
                f"{src}: 'effects.motor.initial_torque' = {o.initial_torque!r} N m needs an integral controller "
                "(effects.motor.ki > 0) that holds it and a speed other than 0 (effects.motor.speed)"
            )
        if abs(o.initial_torque) > o.torque_limit:
            raise SceneError(
                f"{src}: 'effects.motor.initial_torque' = {o.initial_torque!r} N m is beyond "
                f"effects.motor.torque_limit = {o.torque_limit!r} N m"
            )
    if "tensioner" in eff:
        o = eff["tensioner"]
        for key in ("stiffness", "preload", "mass"):
            if getattr(o, key) < 0:
                raise SceneError(f"{src}: 'effects.tensioner.{key}' must be >= 0, got {getattr(o, key)!r}")
    if "rolling_resistance" in eff:
        c = eff["rolling_resistance"].coefficient
        if not 0 <= c < 1:
            raise SceneError(f"{src}: 'effects.rolling_resistance.coefficient' must be in [0, 1), got {c!r}")
    if "gravity" in eff:
        _positive(src, "effects.gravity.g", eff["gravity"].g)
    if "passengers" in eff:
        o = eff["passengers"]
        n = len(o.mass)
        for key in ("step", "board", "alight"):
            if len(getattr(o, key)) != n:
                raise SceneError(
                    f"{src}: 'effects.passengers.{key}' has {len(getattr(o, key))} entries, "
                    f"'effects.passengers.mass' has {n}"
                )
        for i in range(n):
            m, st, b, a = o.mass[i], o.step[i], o.board[i], o.alight[i]
            if not isinstance(m, (int, float)) or m <= 0:
                raise SceneError(f"{src}: 'effects.passengers.mass[{i}]' must be positive [kg], got {m!r}")
            if not isinstance(st, int) or st < 1:
                raise SceneError(f"{src}: 'effects.passengers.step[{i}]' must be a step number >= 1, got {st!r}")
            for key, v in (("board", b), ("alight", a)):
                if isinstance(v, str):
                    if v not in PLACES:
                        raise SceneError(
                            f"{src}: 'effects.passengers.{key}[{i}]' must be a place "
                            f"({', '.join(repr(p) for p in PLACES)}) or a time [s], got {v!r}"
                        )
                elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise SceneError(
                        f"{src}: 'effects.passengers.{key}[{i}]' must be a place "
                        f"({', '.join(repr(p) for p in PLACES)}) or a time [s], got {v!r}"
                    )
        kinds = {isinstance(v, str) for v in list(o.board) + list(o.alight)}
        if len(kinds) > 1:
            raise SceneError(
                f"{src}: 'effects.passengers.board' and 'alight' must all be places or all be times [s], not a mix"
            )
        if kinds == {True}:  # places (the set holds isinstance's answers: it was compared with {str}, never equal)
            for i, (b, a) in enumerate(zip(o.board, o.alight)):
                if b == a:
                    raise SceneError(
                        f"{src}: 'effects.passengers' [{i}] (step {o.step[i]}) boards and alights at the same place "
                        f"{b!r}"
                    )
        else:
            for i, (b, a) in enumerate(zip(o.board, o.alight)):
                if not a > b:
                    raise SceneError(
                        f"{src}: 'effects.passengers.alight[{i}]' = {a!r} s is not after 'board[{i}]' = {b!r} s "
                        f"(step {o.step[i]})"
                    )


#: the sections a scene of each analysis uses (another analysis' run section, or solver keys in a scene that
#: integrates nothing, are refused by _analysis_sections)
USED_SECTIONS = {
    "kinematics": ("scene", "guide", "chain", "sprocket", "kinematics", "outputs"),
    "inverse": ("scene", "guide", "chain", "sprocket", "motion", "outputs"),
    "forward": ("scene", "guide", "chain", "sprocket", "run", "solver", "outputs"),
}


def _defaults(sec, raw_effects, effects, analysis) -> tuple:
    """The dotted keys of the used sections and effects that take a value from the schema's defaults
    because the file does not give them (keys whose default is "not set" are left out)."""
    out = []
    for name in USED_SECTIONS[analysis]:
        cls = SECTION_CLASSES[name]
        out += [f"{name}.{f.name}" for f in cls.fields() if f.default is not None and f.name not in sec[name]]
    for name in effects:
        given = raw_effects.get(name)
        given = given if isinstance(given, dict) else {}
        out += [
            f"effects.{name}.{f.name}"
            for f in EFFECT_OPTIONS[name].fields()
            if (f.default is not None or f.metadata["derived"]) and f.name != "enabled" and f.name not in given
        ]
    return tuple(out)


def _outputs(src, o, analysis, chain):
    allowed = OUTPUTS[analysis]
    variables = list(o.get("variables", OutputsSection.variables))
    for v in variables:
        if not isinstance(v, str) or v not in allowed:
            raise SceneError(
                f"{src}: unknown output {v!r} in 'outputs.variables' for {'an' if analysis == 'inverse' else 'a'} {analysis} scene "
                f"(available: {', '.join(sorted(allowed))})"
            )
    rollers = list(o.get("rollers", OutputsSection.rollers))
    for r in rollers:
        if not isinstance(r, int) or isinstance(r, bool) or not 1 <= r <= chain.n_rollers:
            raise SceneError(f"{src}: 'outputs.rollers' entries must be roller numbers 1..{chain.n_rollers}, got {r!r}")
    if any(v.startswith("roller_") for v in variables) and not rollers:
        raise SceneError(f"{src}: roller outputs asked for but 'outputs.rollers' lists no roller")
    step = o.get("step_accelerometer")
    if "accel_step" in variables and step is None:
        raise SceneError(f"{src}: output 'accel_step' needs 'outputs.step_accelerometer' (a step number)")
    n_steps = chain.n_rollers // chain.links_per_step
    if step is not None and not 1 <= step <= n_steps:
        raise SceneError(f"{src}: 'outputs.step_accelerometer' must be a step 1..{n_steps}, got {step!r}")
    return {"variables": tuple(dict.fromkeys(variables)), "rollers": tuple(rollers), "step_accelerometer": step}


def _analysis_sections(src, sec, analysis):
    need = {
        "kinematics": ("kinematics", ("start", "stop", "step")),
        "inverse": ("motion", ("speed", "duration", "step")),
        "forward": ("run", ("duration", "output_step")),
    }[analysis]
    name, keys = need
    check_sections_belong(src, sec, analysis, name)
    for key in keys:
        if key not in sec[name]:
            raise SceneError(f"{src}: missing value '{name}.{key}' (needed by a {analysis} scene)")
    for key in ("step", "duration", "output_step"):
        if key in sec[name]:
            _positive(src, f"{name}.{key}", sec[name][key])
    step_key = "output_step" if analysis == "forward" else "step"
    if analysis != "kinematics" and sec[name][step_key] > sec[name]["duration"]:
        raise SceneError(
            f"{src}: '{name}.{step_key}' = {sec[name][step_key]!r} s is longer than '{name}.duration' = "
            f"{sec[name]['duration']!r} s: the result would hold one sample"
        )
    if analysis == "kinematics" and not sec[name]["stop"] > sec[name]["start"]:
        raise SceneError(f"{src}: 'kinematics.stop' must be greater than 'kinematics.start'")
    if analysis == "kinematics" and sec[name]["step"] > sec[name]["stop"] - sec[name]["start"]:
        raise SceneError(
            f"{src}: 'kinematics.step' = {sec[name]['step']!r} m is longer than the sweep, 'kinematics.stop' - "
            f"'kinematics.start' = {sec[name]['stop'] - sec[name]['start']:.6g} m: the result would hold one sample"
        )
    if analysis == "inverse" and sec["motion"]["speed"] == 0:
        raise SceneError(f"{src}: 'motion.speed' must be non-zero [m/s]")
    for key in ("rtol", "atol", "max_step", "first_step", "max_wall_time"):
        if key in sec["solver"]:
            _positive(src, f"solver.{key}", sec["solver"][key])
    closure = sec["solver"].get("closure")
    if closure is not None and closure not in CLOSURES:
        raise SceneError(f"{src}: 'solver.closure' must be one of {', '.join(CLOSURES)}, got {closure!r}")
    method = sec["solver"].get("method")
    if method is not None and method.lower() not in SOLVER_METHODS:
        raise SceneError(f"{src}: 'solver.method' must be one of {', '.join(SOLVER_METHODS)}, got {method!r}")
    if "max_result_bytes" in sec["solver"]:
        try:
            parse_bytes(sec["solver"]["max_result_bytes"])
        except ValueError as exc:
            raise SceneError(f"{src}: 'solver.max_result_bytes': {exc}") from None


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Read and validate a TOML scene file.

    Parameters
    ----------
    path : str or Path
        The file, or where no such file exists the name of a shipped scene (``"las-palmas"``,
        ``"sim/las-palmas.toml"``; see :mod:`vibkit.scenes`).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file is missing, not TOML, or has an unknown key, a missing value or a non-physical
        number; the message names the file and the key.
    """
    p = find(path) or Path(path)  # a shipped scene's name ("las-palmas") where no such file exists
    _check_scene_file(p)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"{p}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{p}: cannot read scene file ({exc})") from None
    return parse_scene(text, str(p))


def _check_scene_file(p: Path, what: str = "scene") -> None:
    """A scene (or profile: ``what``) must be a regular file of reasonable size: a FIFO or a device would block
    or never end, a huge file fill the memory."""
    import stat

    try:
        st = p.stat()
    except FileNotFoundError:
        raise SceneError(f"{p}: no such {what} file") from None
    except OSError as exc:
        raise SceneError(f"{p}: cannot read {what} file ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise SceneError(f"{p}: is a folder, expected a {what} file (.toml)")
    if not stat.S_ISREG(st.st_mode):
        raise SceneError(f"{p}: is not a regular file (a FIFO, device or socket); expected a {what} file (.toml)")
    if st.st_size > MAX_SCENE_BYTES:
        raise SceneError(
            f"{p}: is {st.st_size} bytes; a {what} is a small TOML file (at most {MAX_SCENE_BYTES} bytes, 1 MiB)"
        )
