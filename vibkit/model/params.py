"""Parameters of the escalator chain model, as frozen dataclasses.

Every physical quantity is SI and has no silent default: the reference escalator of the study (A. Cuevas López,
Universidad de Sevilla, 2020; summarised in the docs' model page) is built explicitly by :func:`reference_guide`,
:func:`reference_chain` and :func:`reference_sprocket`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "GuideParams",
    "ChainParams",
    "SprocketParams",
    "reference_guide",
    "reference_chain",
    "reference_sprocket",
    "GRAVITY",
    "RAMP",
    "TRAVEL",
]

GRAVITY = 9.81
"""Acceleration of gravity used by the study and ``model.md`` (the default of ``effects.gravity.g``); not
the standard gravity 9.80665 that defines the unit g (:data:`vibkit.runtime.constants.STANDARD_GRAVITY`).
[m/s^2]"""

# here, not in vibkit.model.guide (whose kernels load numba), so that checking a scene's closure loads no compiler
RAMP = 0.1  # width of the cosine ramps at the ends of a telescopic run, as a fraction of Lt
TRAVEL = 1.0 - RAMP  # |delta| / Lt must stay below this for the coordinate map to be monotonic


def _positive(obj, *names):
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{type(obj).__name__}.{name} must be a positive finite number, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class GuideParams:
    """The closed path followed by the roller centres (model.md section 1).

    Parameters
    ----------
    tensioner_length : float
        Length Lt of each telescopic run of the tensioner when undeformed. [m]
    lower_landing, upper_landing : float
        Lengths L1 and L2 of the horizontal landings. [m]
    transition_radius : float
        Radius r_t of the four transition arcs. [m]
    incline_angle : float
        Incline alpha, in [0, pi/2): 0 is a level moving walk, whose transitions turn nothing. [rad]
    incline_length : float
        Length L of the straight incline. [m]
    head_radius : float
        Radius R of both heads; equal to the sprocket pitch radius. [m]
    """

    tensioner_length: float
    lower_landing: float
    upper_landing: float
    transition_radius: float
    incline_angle: float
    incline_length: float
    head_radius: float

    def __post_init__(self):
        _positive(
            self,
            "tensioner_length",
            "lower_landing",
            "upper_landing",
            "transition_radius",
            "incline_length",
            "head_radius",
        )
        if not (0.0 <= self.incline_angle < math.pi / 2):
            raise ValueError(f"GuideParams.incline_angle must be in [0, pi/2) rad, got {self.incline_angle!r}")

    @property
    def perimeter(self) -> float:
        """Undeformed perimeter P0 = 2(L + L1 + L2 + Lt + pi R + 2 alpha r_t). [m]"""
        return 2.0 * (
            self.incline_length
            + self.lower_landing
            + self.upper_landing
            + self.tensioner_length
            + math.pi * self.head_radius
            + 2.0 * self.incline_angle * self.transition_radius
        )

    @property
    def sprocket_centre(self) -> tuple[float, float]:
        """Centre of the upper head (x, z). [m]"""
        a, rt = self.incline_angle, self.transition_radius
        x = (
            self.tensioner_length
            + self.lower_landing
            + 2 * rt * math.sin(a)
            + self.incline_length * math.cos(a)
            + self.upper_landing
        )
        z = 2 * rt * (1 - math.cos(a)) + self.incline_length * math.sin(a)
        return (x, z)


@dataclass(frozen=True, kw_only=True)
class ChainParams:
    """The roller chain (model.md section 3).

    Parameters
    ----------
    link_pitch : float
        Distance between consecutive roller centres. [m]
    roller_radius : float
        Roller radius r_d. [m]
    roller_mass : float
        Point mass per roller (a third of a step plus one pitch of chain). [kg]
    n_rollers : int
        Number of rollers p (= number of links; the chain is closed).
    worn_links : tuple of (int, float)
        Links whose pitch differs from ``link_pitch``: (1-based link number, pitch [m]). Link j
        joins roller j to roller j+1; link p closes the chain on roller 1.
    roller_masses, roller_radii : tuple of (int, float)
        Rollers whose mass [kg] or radius [m] differs from ``roller_mass`` / ``roller_radius``:
        (1-based roller number, value).
    roller_flats : tuple of (int, float)
        Rollers worn flat: (1-based roller number, chord of the flat [m]); the flat acts on the roller's
        own motion (:mod:`vibkit.model.flat_roller`).
    links_per_step : int
        Rollers (links) per step: 3 (the study's 133.33 mm chain under 400 mm steps) or 4 (101.6 mm
        chains). Step s carries rollers links_per_step (s - 1) + 1 ... links_per_step s.
    """

    link_pitch: float
    roller_radius: float
    roller_mass: float
    n_rollers: int
    worn_links: tuple = ()
    roller_masses: tuple = ()
    roller_radii: tuple = ()
    roller_flats: tuple = ()
    links_per_step: int = 3

    def __post_init__(self):
        _positive(self, "link_pitch", "roller_radius", "roller_mass")
        if self.links_per_step not in (3, 4):
            raise ValueError(f"ChainParams.links_per_step must be 3 or 4, got {self.links_per_step!r}")
        if not isinstance(self.n_rollers, int) or self.n_rollers < 3:
            raise ValueError(f"ChainParams.n_rollers must be an integer >= 3, got {self.n_rollers!r}")
        for link, pitch in self.worn_links:
            if not (isinstance(link, int) and 1 <= link <= self.n_rollers):
                raise ValueError(f"ChainParams.worn_links: link number must be 1..{self.n_rollers}, got {link!r}")
            if not (math.isfinite(pitch) and pitch > 0):
                raise ValueError(f"ChainParams.worn_links: pitch of link {link} must be positive, got {pitch!r}")
        for name in ("roller_masses", "roller_radii", "roller_flats"):
            for roller, value in getattr(self, name):
                if not (isinstance(roller, int) and 1 <= roller <= self.n_rollers):
                    raise ValueError(f"ChainParams.{name}: roller number must be 1..{self.n_rollers}, got {roller!r}")
                if not (math.isfinite(value) and value > 0):
                    raise ValueError(f"ChainParams.{name}: value of roller {roller} must be positive, got {value!r}")

    def _by_roller(self, base, overrides):
        import numpy as np

        out = np.full(self.n_rollers, float(base))
        for roller, value in overrides:
            out[roller - 1] = value
        return out

    def masses(self):
        """Mass of every roller. [kg]"""
        return self._by_roller(self.roller_mass, self.roller_masses)

    def radii(self):
        """Radius of every roller. [m]"""
        return self._by_roller(self.roller_radius, self.roller_radii)

    def pitches(self):
        """Pitch of every link, link j joining roller j to j+1 (the last closing on roller 1). [m]"""
        import numpy as np

        out = np.full(self.n_rollers, float(self.link_pitch))
        for link, pitch in self.worn_links:
            out[link - 1] = pitch
        return out


@dataclass(frozen=True, kw_only=True)
class SprocketParams:
    """The drive sprocket at the upper head (model.md section 4).

    Parameters
    ----------
    teeth : int
        Number of teeth Z.
    base_width, tip_width, tooth_height : float
        Trapezoidal tooth: width B at the root circle, b at the tip, height h. [m]
    mass : float
        Sprocket mass. [kg]
    inertia : float
        Moment of inertia about the axle. [kg m^2]
    pitch : float or None
        The chain pitch its teeth are cut for; None: the pitch of the chain it drives (a new chain
        on a new sprocket). A worn chain keeps its original sprocket: give the original pitch. [m]
    """

    teeth: int
    base_width: float
    tip_width: float
    tooth_height: float
    mass: float
    inertia: float
    pitch: float | None = None

    def __post_init__(self):
        if not isinstance(self.teeth, int) or self.teeth < 3:
            raise ValueError(f"SprocketParams.teeth must be an integer >= 3, got {self.teeth!r}")
        _positive(self, "base_width", "tip_width", "tooth_height", "mass", "inertia")
        if self.pitch is not None:
            _positive(self, "pitch")

    def pitch_radius(self, link_pitch: float) -> float:
        """R^P = L_link / (2 sin(pi / Z)): the radius at which rollers ``link_pitch`` apart sit one
        tooth pitch apart (the sprocket's pitch radius for links of its own pitch). [m]"""
        return link_pitch / (2.0 * math.sin(math.pi / self.teeth))

    def cut_pitch(self, chain_pitch: float) -> float:
        """The pitch the teeth are cut for: ``pitch``, or where it is not set ``chain_pitch``. [m]"""
        return float(self.pitch) if self.pitch is not None else float(chain_pitch)

    @property
    def tooth_pitch(self) -> float:
        """Angle between teeth psi = 2 pi / Z. [rad]"""
        return 2.0 * math.pi / self.teeth


def sprocket_teeth_for(link_pitch: float, design_radius: float) -> int:
    """Largest Z whose pitch radius does not exceed ``design_radius``: floor(pi / asin(L / 2R))."""
    return int(math.floor(math.pi / math.asin(link_pitch / (2.0 * design_radius))))


def reference_chain() -> ChainParams:
    """The study's chain: pitch 0.4/3 m, rollers of 0.035 m and 8 kg, p = 159."""
    return ChainParams(link_pitch=0.4 / 3.0, roller_radius=0.035, roller_mass=8.0, n_rollers=159)


def reference_sprocket() -> SprocketParams:
    """The study's sprocket: Z = 28 trapezoidal teeth, 250.62 kg, 43.78 kg m^2."""
    z = sprocket_teeth_for(0.4 / 3.0, 0.6)
    return SprocketParams(teeth=z, base_width=0.060, tip_width=0.040, tooth_height=0.070, mass=250.62, inertia=43.78)


def reference_guide() -> GuideParams:
    """The study's guide (rise 3 m at 30 deg) with head radius equal to the sprocket pitch radius."""
    chain = reference_chain()
    radius = reference_sprocket().pitch_radius(chain.link_pitch)
    return GuideParams(
        tensioner_length=0.4,
        lower_landing=0.8,
        upper_landing=0.8,
        transition_radius=1.5,
        incline_angle=math.radians(30.0),
        incline_length=5.19615,
        head_radius=radius,
    )
