"""The scene schema: every key of a scene file, with its unit, default, plausible range and meaning.

Each section of a scene (``[scene]``, ``[guide]``, ``[chain]``, ... ``[outputs]``) and each effect
(``[effects.contact]``, ...) is a frozen dataclass here; each field carries its TOML type(s), unit,
plausible range and doc in ``dataclasses.field(metadata=...)``. Everything else is derived from these
classes: :data:`SECTIONS` and :data:`EFFECTS` (key -> type, used by the loader and by sweeps),
:data:`RANGES` (the plausible ranges the loader enforces), :func:`schema_table` (the Markdown table of
the documentation) and the defaults of a loaded scene. :mod:`vibkit.model.scene` reads the TOML text,
checks it against this schema and builds these objects; the analyses read typed attributes
(``scene.run.start``, ``effects["contact"].exponent``) and never restate a default. The outputs an
analysis may produce (:data:`OUTPUTS`, with their columns :data:`OUTPUT_COLUMNS`) and the effects it applies
(:data:`ANALYSIS_EFFECTS`) are declared here too; the compiled kernels name one switch per effect of
:data:`EFFECT_OPTIONS` (:mod:`vibkit.model.slots`).

A field is *required* when the scene must give it (``required=True`` in its metadata; its dataclass
default is ``None``). A field whose default is ``None`` and is not required means "not set": its doc
says what happens then (``solver.rtol``: chosen from the contact stiffness).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

from ..runtime.budget import DEFAULT_MAX_RESULT_BYTES, DEFAULT_MAX_WALL_TIME
from .params import GRAVITY, reference_chain

__all__ = [
    "ANALYSIS_EFFECTS",
    "ATOL_PER_RTOL",
    "OUTPUTS",
    "OUTPUT_COLUMNS",
    "EFFECT_OPTIONS",
    "EFFECTS",
    "GEOMETRY_RANGES",
    "RANGES",
    "SceneError",
    "SECTION_CLASSES",
    "SECTIONS",
    "check_geometry_range",
    "effect_options",
    "gravity_of",
    "key_units",
    "nominal_speed",
    "schema_fields",
    "schema_table",
]


class SceneError(ValueError):
    """A scene file that cannot be used; the message names the file and the key."""


#: the absolute tolerance of a forward run that sets no ``solver.atol`` is rtol times this [m, rad]
ATOL_PER_RTOL = 1e-2


def key(unit, doc, default=None, *, types=(float,), required=False, range=None, derived=False, positive=False):
    """A schema field: TOML type(s), unit, default, plausible ``range`` = (lo, hi, note) and doc.

    ``derived``: the default depends on other keys (its doc says how); the dataclass default is None.
    ``positive``: the range's lower end is excluded (the loader refuses it: ``must be positive``).
    """
    meta = {
        "unit": unit,
        "doc": doc,
        "types": types,
        "required": required,
        "range": range,
        "derived": derived,
        "positive": positive,
    }
    if isinstance(default, (list, dict)):
        raise TypeError("a schema default must be immutable (use a tuple)")
    return dataclasses.field(default=default, metadata=meta)


_RC = reference_chain()


class _Section:
    """Base of the section and effect classes: built from the TOML table, defaults from the schema."""

    @classmethod
    def from_mapping(cls, data: Mapping):
        return cls(**dict(data))

    @classmethod
    def fields(cls):
        return dataclasses.fields(cls)


@dataclasses.dataclass(frozen=True)
class SceneSection(_Section):
    name: str = key("", "the scene's name; not set: the file's stem", types=(str,), derived=True)
    analysis: str = key("", '"kinematics", "inverse" or "forward"', types=(str,), required=True)
    description: str = key("", "one line on what the scene is", "", types=(str,))


@dataclasses.dataclass(frozen=True)
class GuideSection(_Section):
    tensioner_length: float = key("m", "length Lt of each telescopic run of the tensioner, undeformed", required=True)
    lower_landing: float = key("m", "length L1 of the horizontal lower landing", required=True)
    upper_landing: float = key("m", "length L2 of the horizontal upper landing", required=True)
    transition_radius: float = key("m", "radius r_t of the four transition arcs", required=True)
    incline_angle_deg: float = key("deg", "angle of the incline, in [0, 90) (0: a level moving walk)", required=True)
    incline_length: float = key("m", "length L of the straight incline", required=True)
    head_radius: float | str = key(
        "m",
        'radius of the heads, or "sprocket": where the rollers seat on the sprocket\'s teeth, p / (2 sin(pi/Z)) '
        "for the chain's pitch p (the sprocket's pitch radius for a chain of the sprocket's pitch, larger for an "
        "elongated chain)",
        "sprocket",
        types=(float, str),
    )


@dataclasses.dataclass(frozen=True)
class ChainSection(_Section):
    link_pitch: float = key(
        "m", "distance between consecutive roller centres", required=True, range=(0.02, 0.5, "m (101.6 mm is 0.1016 m)")
    )
    roller_radius: float = key(
        "m",
        "roller radius r_d, less than half the pitch",
        _RC.roller_radius,
        range=(0.001, 0.25, "m (35 mm is 0.035 m)"),
    )
    roller_mass: float = key(
        "kg", "point mass per roller (a step's share, 1 / links_per_step, plus one pitch of chain)", _RC.roller_mass
    )
    n_rollers: int | str = key(
        "",
        'number of rollers, or "fill": as many links of link_pitch as fit the guide (an elongated chain keeps them)',
        "fill",
        types=(int, str),
    )
    worn_link: int = key(
        "",
        "number (1..n) of one link of another pitch (with worn_link_pitch): shorthand for worn_links = "
        "[[worn_link, worn_link_pitch]]; not set: none",
        types=(int,),
    )
    worn_link_pitch: float = key("m", "pitch of the worn link (with worn_link); not set: no worn link")
    worn_links: tuple = key(
        "[1, m]",
        "links of another pitch, [[link, pitch_m], ...] (link 1..n joins roller link to the next); not set: none",
        types=(list,),
    )
    elongation_percent: float = key(
        "%",
        "uniform elongation of every link by wear: each pitch is link_pitch (1 + e/100) on a sprocket cut for "
        "link_pitch",
        0.0,
        range=(-1.0, 10.0, "% (a chain is replaced at about 3 %)"),
    )
    roller_radius_by_roller: tuple = key(
        "[1, m]",
        "rollers of another radius (a damaged roller), [[roller, radius_m], ...]; not set: none",
        types=(list,),
    )
    roller_mass_by_roller: tuple = key(
        "[1, kg]", "rollers of another mass, [[roller, mass_kg], ...]; not set: none", types=(list,)
    )
    roller_flat_by_roller: tuple = key(
        "[1, m]",
        "rollers worn flat, [[roller, flat_length_m], ...] (the chord of the flat; the roller's centre dips "
        "toward its track once a turn, in the stored rollers' motion); not set: none",
        types=(list,),
    )
    links_per_step: int = key(
        "", "rollers (links) per step: 3 (133.33 mm chains) or 4 (101.6 mm chains)", 3, types=(int,)
    )


@dataclasses.dataclass(frozen=True)
class SprocketSection(_Section):
    teeth: int = key("", "number of teeth (>= 3)", types=(int,), required=True)
    base_width: float = key("m", "tooth width at the root", required=True)
    tip_width: float = key("m", "tooth width at the tip", required=True)
    tooth_height: float = key("m", "tooth height", required=True)
    mass: float = key("kg", "sprocket mass", required=True)
    inertia: float = key("kg m^2", "sprocket moment of inertia", required=True)
    pitch: float = key(
        "m",
        "the chain pitch the teeth are cut for (a worn chain keeps its original sprocket); not set: the chain's "
        "link_pitch",
        derived=True,
    )


@dataclasses.dataclass(frozen=True)
class KinematicsSection(_Section):
    start: float = key("m", "first advance of roller 1 (kinematics)", required=True)
    stop: float = key("m", "last advance of roller 1 (kinematics)", required=True)
    step: float = key("m", "advance between configurations (kinematics)", required=True)


_SPEED = (-10.0, 10.0, "m/s")


@dataclasses.dataclass(frozen=True)
class MotionSection(_Section):
    speed: float = key(
        "m/s", "imposed speed of roller 1 along the guide, heads included (inverse)", required=True, range=_SPEED
    )
    duration: float = key("s", "length of the run (inverse)", required=True)
    step: float = key("s", "output step (inverse)", required=True)
    start: float = key("m", "position of roller 1 at t = 0 (reduced modulo the perimeter)", 0.0)


@dataclasses.dataclass(frozen=True)
class RunSection(_Section):
    duration: float = key("s", "length of the run (forward)", required=True)
    output_step: float = key("s", "output step (forward)", required=True)
    start: float = key("m", "position of roller 1 at t = 0 (reduced modulo the perimeter)", 0.0)
    initial_speed: float = key("m/s", "chain speed at t = 0", 0.0, range=_SPEED)
    seed: int = key("", "a seed, recorded; read by no analysis; not set: none", types=(int,))


@dataclasses.dataclass(frozen=True)
class SolverSection(_Section):
    method: str = key("", "integrator (vibkit.analyses.integrate.METHODS)", "dopri5", types=(str,))
    rtol: float = key("", "relative tolerance; not set: chosen from the contact stiffness", range=(1e-14, 0.1, ""))
    atol: float = key(
        "",
        f"absolute tolerance (m of delta, rad of the sprocket); not set: rtol x {ATOL_PER_RTOL:g}",
        range=(0.0, 1.0, ""),
    )
    max_step: float = key("s", "largest integrator step", math.inf)
    first_step: float = key("s", "first integrator step; not set: the integrator's choice")
    max_wall_time: float = key(
        "s", f"wall-time budget; not set: $VIBKIT_MAX_WALL_TIME, else {DEFAULT_MAX_WALL_TIME:g} s"
    )
    max_result_bytes: float | str = key(
        "bytes",
        'result-size limit ("2GiB" or a number); not set: $VIBKIT_MAX_RESULT_BYTES, else '
        f"{DEFAULT_MAX_RESULT_BYTES / 1024**3:g} GiB",
        types=(float, str),
    )
    events: bool = key("", "end steps where a roller crosses a curvature jump of the guide", True, types=(bool,))
    check: bool = key("", "run again tighter and say whether the result converged", False, types=(bool,))
    check_min_rtol: float = key(
        "",
        "the tightest tolerance the convergence check tries",
        1e-12,
        range=(1e-14, 0.1, "(the tightest tolerance the convergence check tries)"),
    )
    closure: str = key(
        "",
        '"table" (over one pitch), "exact" (solved at every evaluation) or "runs" (solved run by run)',
        "table",
        types=(str,),
    )

    def atol_for(self, rtol: float) -> float:
        """The absolute tolerance of a run at ``rtol``: ``atol`` if given, else rtol x :data:`ATOL_PER_RTOL`."""
        return self.atol if self.atol is not None else rtol * ATOL_PER_RTOL


@dataclasses.dataclass(frozen=True)
class OutputsSection(_Section):
    variables: tuple = key("", "names of the outputs", ("delta", "closure_residual"), types=(list,))
    rollers: tuple = key("", "1-based numbers of the rollers whose motion is stored", (), types=(list,))
    step_accelerometer: int = key(
        "", "1-based step carrying the accelerometer of accel_step; not set: none", types=(int,)
    )


# effects -----------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class GravityOptions(_Section):
    enabled: bool = key("", "false switches the effect off", True, types=(bool,))
    g: float = key(
        "m/s^2",
        "acceleration of gravity (the study's value; for none, leave the effect out)",
        GRAVITY,
        range=(0.0, 1000.0, "m/s^2"),
        positive=True,
    )


@dataclasses.dataclass(frozen=True)
class ContactOptions(_Section):
    stiffness: float = key(
        "N/m^exponent",
        "roller-tooth contact stiffness",
        required=True,
        range=(0.0, 1e16, "N/m^exponent (steel about 1e10)"),
        positive=True,
    )
    exponent: float = key(
        "", "force-indentation exponent (1 linear, 1.5 Hertz)", 1.5, range=(1.0, 3.0, "(1 linear, 1.5 Hertz)")
    )
    damping: float = key("s/m", "contact damping (Hunt-Crossley)", 0.0, range=(0.0, 1e3, "s/m"))


@dataclasses.dataclass(frozen=True)
class MotorOptions(_Section):
    kp: float = key(
        "N m s",
        "proportional gain (per rad/s of speed error); 0 only with ki > 0 (an integral controller)",
        required=True,
        range=(0.0, 1e8, "N m s/rad"),
    )
    ki: float = key(
        "N m", "integral gain of the speed controller (per rad of angle error)", 0.0, range=(0.0, 1e9, "N m/rad")
    )
    speed: float = key("m/s", "nominal chain speed", required=True, range=(-10.0, 10.0, "m/s"))
    torque_limit: float = key("N m", "largest motor torque", math.inf, range=(0.0, 1e8, "N m"), positive=True)
    initial_torque: float = key(
        "N m",
        "torque that drives the chain at t = 0, along its motion (negative: brakes it): a run started in steady "
        "running against a known load; the controller's integral starts there (ki > 0) and the sprocket with its "
        "driving flanks touching the rollers; 0: the meshed start, teeth clear",
        0.0,
        range=(-1e8, 1e8, "N m"),
    )


@dataclasses.dataclass(frozen=True)
class PassengersOptions(_Section):
    mass: tuple = key("kg", "mass of each passenger", required=True, types=(list,))
    step: tuple = key("", "1-based step of each passenger", required=True, types=(list,))
    board: tuple = key(
        "", 'where (a place) or when [s] each boards; not set: "lower_landing"', types=(list,), derived=True
    )
    alight: tuple = key(
        "", 'where (a place) or when [s] each alights; not set: "upper_landing"', types=(list,), derived=True
    )

    @classmethod
    def from_mapping(cls, data: Mapping):
        d = {k: tuple(v) for k, v in dict(data).items()}
        n = len(d.get("mass", ()))
        # by place unless times are given: a step boards at the lower landing, alights at the upper
        d.setdefault("board", ("lower_landing",) * n)
        d.setdefault("alight", ("upper_landing",) * n)
        return cls(**d)


@dataclasses.dataclass(frozen=True)
class TensionerOptions(_Section):
    stiffness: float = key("N/m", "tensioner spring stiffness", 0.0, range=(0.0, 1e12, "N/m"))
    preload: float = key("N", "tensioner spring preload", 0.0, range=(0.0, 1e9, "N"))
    mass: float = key("kg", "tensioner carriage mass", 0.0, range=(0.0, 1e6, "kg"))


@dataclasses.dataclass(frozen=True)
class RollingResistanceOptions(_Section):
    coefficient: float = key("", "rolling-resistance coefficient, in [0, 1)", required=True)


#: section name -> its class, in the order of a scene file
SECTION_CLASSES = {
    "scene": SceneSection,
    "guide": GuideSection,
    "chain": ChainSection,
    "sprocket": SprocketSection,
    "kinematics": KinematicsSection,
    "motion": MotionSection,
    "run": RunSection,
    "solver": SolverSection,
    "outputs": OutputsSection,
}

#: effect name -> its options class
EFFECT_OPTIONS = {
    "gravity": GravityOptions,
    "contact": ContactOptions,
    "motor": MotorOptions,
    "passengers": PassengersOptions,
    "tensioner": TensionerOptions,
    "rolling_resistance": RollingResistanceOptions,
}


#: the outputs each analysis may produce (``outputs.variables``)
OUTPUTS = {
    "kinematics": {"delta", "s1", "roller_position", "closure_residual"},
    "inverse": {
        "delta",
        "delta_dot",
        "delta_ddot",
        "link_tension",
        "drive_force",
        "closure_residual",
        "chain_speed",
        "sprocket_angle",
        "sprocket_speed",
        "roller_position",
        "roller_velocity",
        "roller_acceleration",
        "energy",
    },
    "forward": {
        "delta",
        "delta_dot",
        "sprocket_angle",
        "sprocket_speed",
        "motor_torque",
        "chain_speed",
        "link_tension",
        "indentation",
        "contact_force",
        "flank_force",
        "roller_position",
        "roller_velocity",
        "roller_acceleration",
        "closure_residual",
        "tensioner_displacement",
        "accel_step",
        "energy",
        "s0",
    },
}

#: values per sample of each output, for the size of a sweep's kept series (vibkit.sweep.limits): n the
#: chain's rollers, t the sprocket's teeth, r the rollers asked for (outputs.rollers), a number that many
#: (an output that gives several variables, as energy does, counts them all; each of those is one)
OUTPUT_COLUMNS = {
    "delta": "1",
    "delta_dot": "1",
    "delta_ddot": "1",
    "s0": "1",
    "s1": "1",
    "closure_residual": "1",
    "chain_speed": "1",
    "drive_force": "1",
    "sprocket_angle": "1",
    "sprocket_speed": "1",
    "motor_torque": "1",
    "tensioner_displacement": "1",
    "link_tension": "n",
    "contact_force": "t",
    "indentation": "t",
    "flank_force": "2t",
    "roller_position": "2r",
    "roller_velocity": "2r",
    "roller_acceleration": "2r",
    "energy": "4",
    "accel_step": "3",
}
if set(OUTPUT_COLUMNS) != set().union(*OUTPUTS.values()):
    raise RuntimeError(
        "vibkit.model.schema: OUTPUT_COLUMNS and OUTPUTS disagree on "
        + ", ".join(sorted(set(OUTPUT_COLUMNS) ^ set().union(*OUTPUTS.values())))
    )

#: the effects each analysis applies (a scene of the analysis refuses the others)
ANALYSIS_EFFECTS = {
    "kinematics": frozenset(),
    "inverse": frozenset({"gravity", "passengers", "tensioner"}),
    "forward": frozenset(EFFECT_OPTIONS),
}


def _types(f):
    t = f.metadata["types"]
    return t[0] if len(t) == 1 else t


#: section -> key -> TOML type(s) (derived from the schema)
SECTIONS = {name: {f.name: _types(f) for f in cls.fields()} for name, cls in SECTION_CLASSES.items()}
#: effect -> key -> TOML type(s) (derived from the schema)
EFFECTS = {name: {f.name: _types(f) for f in cls.fields()} for name, cls in EFFECT_OPTIONS.items()}


def schema_fields():
    """(dotted section, field) for every key of the schema, in the order of a scene file."""
    out = [(name, f) for name, cls in SECTION_CLASSES.items() for f in cls.fields()]
    out += [(f"effects.{name}", f) for name, cls in EFFECT_OPTIONS.items() for f in cls.fields()]
    return out


#: dotted key -> (lo, hi, note): the plausible ranges the loader enforces (derived from the schema)
RANGES = {f"{sec}.{f.name}": f.metadata["range"] for sec, f in schema_fields() if f.metadata["range"]}

#: the escalator's physical keys: plausible ranges checked after each is found positive (a length in millimetres
#: typed as metres is refused with the metres it meant); dotted key -> (lo, hi, unit)
GEOMETRY_RANGES = {
    "guide.tensioner_length": (0.01, 10.0, "m"),
    "guide.lower_landing": (0.0, 50.0, "m"),
    "guide.upper_landing": (0.0, 50.0, "m"),
    "guide.transition_radius": (0.05, 50.0, "m"),
    "guide.incline_length": (0.1, 500.0, "m"),
    "guide.head_radius": (0.02, 5.0, "m"),
    "chain.roller_mass": (0.01, 200.0, "kg"),
    "sprocket.base_width": (0.001, 0.5, "m"),
    "sprocket.tip_width": (0.0005, 0.5, "m"),
    "sprocket.tooth_height": (0.001, 0.5, "m"),
    "sprocket.mass": (1.0, 20000.0, "kg"),
    "sprocket.inertia": (0.01, 20000.0, "kg m^2"),
    "sprocket.pitch": (0.02, 0.5, "m"),
}


def check_geometry_range(src, key, value) -> None:
    """``key`` = ``value`` within :data:`GEOMETRY_RANGES` (a SceneError naming the file, the key and, for a length
    a thousand times too large, the metres it meant)."""
    if key not in GEOMETRY_RANGES or isinstance(value, bool) or not isinstance(value, (int, float)):
        return
    lo, hi, unit = GEOMETRY_RANGES[key]
    v = float(value)
    if math.isfinite(v) and lo <= v <= hi:
        return
    hint = (
        f"; did you mean {v / 1000:.5g} m? (millimetres typed as metres)"
        if unit == "m" and lo <= v / 1000 <= hi
        else ""
    )
    raise SceneError(f"{src}: '{key}' = {v:g} {unit} is not plausible: expected {lo:g}-{hi:g} {unit}{hint}")


def effect_options(effects: Mapping | None) -> dict:
    """Effect name -> typed options, from a scene's effects or a mapping of plain option tables.

    Typed options pass through; a plain table (benchmarks and tests build them) gets the schema's
    defaults for the keys it leaves out.
    """
    out = {}
    for name, opts in (effects or {}).items():
        cls = EFFECT_OPTIONS[name]
        out[name] = opts if isinstance(opts, cls) else cls.from_mapping(opts)
    return out


def gravity_of(effects: Mapping) -> float:
    """The acceleration of gravity of a run [m/s^2]: the gravity effect's ``g``, else the schema's default
    (passengers and rolling resistance weigh with it even where the gravity effect is off)."""
    return effects["gravity"].g if "gravity" in effects else GravityOptions.g


def nominal_speed(effects: Mapping, run: RunSection) -> float:
    """The nominal chain speed of a forward run [m/s]: the motor's set speed, else the initial speed."""
    return effects["motor"].speed if "motor" in effects else run.initial_speed


def key_units() -> dict:
    """Dotted key -> unit of every number key (``"1"`` for a pure number), as a coordinate's ``units``."""
    out = {}
    for sec, f in schema_fields():
        types = f.metadata["types"]
        if float in types or int in types:
            out[f"{sec}.{f.name}"] = f.metadata["unit"] or "1"
        elif bool in types or str in types:
            out[f"{sec}.{f.name}"] = ""
    return out


def _fmt(v):
    """A default as TOML writes it ("not set" for None)."""
    if v is None:
        return "not set"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, tuple):
        return "[" + ", ".join(repr(x) for x in v) + "]"
    if isinstance(v, str):
        return f'"{v}"'
    return f"{v:g}" if isinstance(v, float) else str(v)


def schema_table() -> str:
    """The schema as a Markdown table: section, key, unit, default, plausible range, meaning."""
    rows = [
        "| section | key | unit | default | range | meaning |",
        "|---|---|---|---|---|---|",
    ]
    for sec, f in schema_fields():
        m = f.metadata
        default = "required" if m["required"] else "(see meaning)" if m["derived"] else _fmt(f.default)
        rg = m["range"] or GEOMETRY_RANGES.get(f"{sec}.{f.name}")
        rng = f"{'(' if m.get('positive') else '['}{rg[0]:g}, {rg[1]:g}]" if rg else ""
        rows.append(f"| [{sec}] | {f.name} | {m['unit']} | {default} | {rng} | {m['doc']} |")
    return "\n".join(rows) + "\n"
