"""The scene of a profiled escalator: what the profile says, the rest from standard step-chain proportions.

:func:`scene_text` writes the TOML scene of a :class:`~vibkit.model.profile.Profile` (its comments say
which values came from the profile and which were filled, and from what); :func:`profile_scene` loads
it and refuses a geometry that cannot run, naming the profile key to change:

- the chain must close on the guide within the tensioner's travel (``chain.n_links`` against
  ``geometry.rise``/``geometry.incline_deg``);
- no roller may sit inside a tooth at t = 0 (``chain.roller_radius`` against teeth cut for the pitch);
- the heads' radius is the sprocket's pitch radius (the scene says ``head_radius = "sprocket"``).

Filled from the reference escalator of the study (:mod:`vibkit.model.params`), scaled with the pitch
where a size follows the chain: roller radius and tooth size (base, tip, height) in proportion to the
pitch; the mass per metre of chain and steps (60 kg/m: 8 kg per roller at 133.33 mm) and so the
roller mass; the sprocket's mass and inertia with its pitch radius (a disc of the reference's
thickness: R^2 and R^4). Landings (0.8 m), transitions (1.5 m radius) and the tensioner's runs
(0.4 m) are the reference's; the incline follows the rise (its length from the rise less the
transitions' height) or the number of links (the loop n L plus the reference's tensioner slack).
The contact (k = 1e6 N/m^1.5, damping 0.3 s/m) is the reference's; the tensioner's preload, where the
profile gives none, keeps every link in tension (:func:`default_preload`).

A driven chain (forward scenes): a real unit's drive works all the time against the steps' rolling resistance,
the chain's articulation and the handrails, so its teeth always carry load; a chain without friction coasts at
steady speed in the teeth's backlash.  The scene carries that running resistance as ``[effects]
rolling_resistance`` (mu m g on every roller, the no-load drive power mu g M v for a chain and steps of mass M
at speed v; :func:`running_resistance`): the profile's ``drive.no_load_power``, else
:data:`TYPICAL_RESISTANCE_N_PER_M` over the loop.  Its speed controller is a PI controller tuned to the unit's
inertia (:func:`drive_gains`), which holds the rated speed against the resistance with no steady error, started
in steady running (``initial_torque``, :func:`steady_torque`: the teeth carry the drive from the first sample);
the default preload adds what the resistance takes from the slack strand (:func:`default_preload`).
``no_load_power = 0`` gives the coasting scene (no running resistance, the reference's P controller, kp = 600
N m s).  The study's own scenes (``sim/``) keep their published settings.
"""

from __future__ import annotations

import math

import numpy as np

from .params import TRAVEL, reference_chain, reference_guide, reference_sprocket
from .scene import Scene, SceneError, parse_scene

__all__ = [
    "profile_scene",
    "scene_text",
    "roller_radius_of",
    "link_count",
    "geometry_note",
    "running_resistance",
    "drive_gains",
    "default_preload",
    "steady_torque",
    "MASS_PER_METRE",
    "TYPICAL_RESISTANCE_N_PER_M",
]

_RC, _RG, _RS = reference_chain(), reference_guide(), reference_sprocket()
REFERENCE_PITCH = _RC.link_pitch
#: mass of chain and steps per metre of chain of the reference (8 kg per roller at 133.33 mm) [kg/m]
MASS_PER_METRE = _RC.roller_mass / REFERENCE_PITCH
#: the reference chain's tensioner displacement at rest, (P0 - n L) / 2 [m]
REFERENCE_SLACK = (_RG.perimeter - _RC.n_rollers * REFERENCE_PITCH) / 2.0
DEFAULT_INCLINE_DEG = 30.0
#: forward runs: settle after the start at speed, then enough link passes to read a frequency [s]
DEFAULT_DURATION = {"forward": 20.0, "inverse": 10.0}
OUTPUT_STEP = 0.005
#: typical running resistance of an escalator's chain and steps with its handrails, per metre of the chain's
#: loop [N/m]: Transport for London's figure for a 15 m, 30 degree Underground escalator at 0.75 m/s, "allowing
#: 2 kW more for friction" (The Mathematics of Escalators on the London Underground, TfL Mechanical Engineering),
#: spread over the incline's two strands (2 x 15 m; the landings and heads left out, so rather high than low):
#: 2000 W / 0.75 m/s / 30 m.  About 0.9 kW of no-load drive power for the reference escalator at 0.5 m/s.
TYPICAL_RESISTANCE_N_PER_M = 2000.0 / 0.75 / 30.0
#: the speed controller's closed loop: natural frequency [rad/s] and damping ratio (:func:`drive_gains`)
DRIVE_BANDWIDTH, DRIVE_DAMPING = 100.0, 0.7
G = 9.81


def roller_radius_of(profile) -> tuple[float, str]:
    """``(radius [m], where it came from)``: the profile's ``chain.roller_radius``, else the reference
    roller scaled with the pitch (as the profile's scene is built)."""
    if profile.roller_radius is not None:
        return float(profile.roller_radius), "chain.roller_radius"
    radius = _RC.roller_radius * profile.nominal_pitch / REFERENCE_PITCH
    return float(radius), f"filled: reference {1000 * _RC.roller_radius:g} mm x pitch / 133.33 mm"


def _fmt(v) -> str:
    return repr(float(v)) if isinstance(v, float) else str(v)


class _Filled:
    """The scene's numbers, each with where it came from (a profile key or what filled it)."""

    def __init__(self, profile):
        p = profile
        self.profile = p
        self.notes = []
        scale = p.nominal_pitch / REFERENCE_PITCH
        self.scale = scale
        self.pitch = p.nominal_pitch
        self.roller_radius, self.roller_src = roller_radius_of(p)
        self.roller_mass = MASS_PER_METRE * self.pitch
        self.teeth = p.teeth
        self.base_width, self.tip_width, self.tooth_height = (
            _RS.base_width * scale,
            _RS.tip_width * scale,
            _RS.tooth_height * scale,
        )
        rp = self.pitch / (2.0 * math.sin(math.pi / self.teeth))
        ratio = rp / _RS.pitch_radius(REFERENCE_PITCH)
        self.sprocket_mass, self.inertia = _RS.mass * ratio**2, _RS.inertia * ratio**4
        self.pitch_radius = rp
        self._guide()

    def _guide(self):
        p = self.profile
        a_deg = p.incline_deg if p.incline_deg is not None else DEFAULT_INCLINE_DEG
        a = math.radians(a_deg)
        self.incline_deg = a_deg
        rt, l1, l2, lt = _RG.transition_radius, _RG.lower_landing, _RG.upper_landing, _RG.tensioner_length
        fixed = l1 + l2 + lt + math.pi * self.pitch_radius + 2.0 * a * rt  # half the perimeter less L
        # the loop from the geometry: an escalator's rise, or a moving walk's length between the heads
        if p.rise is not None:
            length = (p.rise - 2.0 * rt * (1.0 - math.cos(a))) / math.sin(a)
            if length <= 0:
                raise SceneError(
                    f"{p.source}: 'geometry.rise' = {p.rise:g} m is lower than the transitions alone climb "
                    f"({2 * rt * (1 - math.cos(a)):.3g} m at {a_deg:g} deg with the standard 1.5 m transition arcs)"
                )
            self.length_src = (
                f"from geometry.rise {p.rise:g} m and incline {a_deg:g} deg, less the transitions' "
                f"{2 * rt * (1 - math.cos(a)):.3f} m"
            )
        elif p.length is not None:
            # the heads' axles are lt + l1 + 2 rt sin(a) + L cos(a) + l2 apart in plan (tensioner at rest)
            ends = lt + l1 + l2 + 2.0 * rt * math.sin(a)
            length = (p.length - ends) / math.cos(a)
            if length <= 0:
                raise SceneError(
                    f"{p.source}: 'geometry.length' = {p.length:g} m is shorter than a moving walk's heads, landings "
                    f"and tensioner alone ({ends:.3g} m at {a_deg:g} deg): give the length between the heads' axles"
                )
            self.length_src = (
                f"from geometry.length {p.length:g} m between the heads at {a_deg:g} deg, less the landings', "
                f"tensioner's{' and transitions' if a > 0 else ''} {ends:.3f} m"
            )
        if p.geometry_given:
            perimeter = 2.0 * (length + fixed)
            if p.n_links is None:
                k = p.links_per_step
                steps = round((perimeter - 2.0 * REFERENCE_SLACK) / (self.pitch * k))
                self.n_links, self.links_src = (
                    steps * k,
                    (
                        f"filled: whole {'pallets' if p.is_walk else 'steps'} of {k} links that close the loop of "
                        f"{perimeter:.4f} m with the tensioner near the reference's {1000 * REFERENCE_SLACK:.0f} mm"
                    ),
                )
            else:
                self.n_links, self.links_src = p.n_links, "chain.n_links"
        else:
            # no geometry: an escalator of the common incline whose rise follows from the count (said in the
            # scene's comments and notes: :func:`geometry_note`)
            self.n_links, self.links_src = p.n_links, "chain.n_links"
            length = (self.n_links * self.pitch) / 2.0 + REFERENCE_SLACK - fixed
            if length <= 0:
                raise SceneError(
                    f"{p.source}: 'chain.n_links' = {p.n_links} links of {1000 * self.pitch:g} mm are too few "
                    f"for an escalator's landings and heads (at least "
                    f"{math.ceil(2 * (fixed - REFERENCE_SLACK) / self.pitch) + 1}); give the rise (geometry.rise)"
                )
            self.length_src = (
                f"from chain.n_links {self.n_links} x {1000 * self.pitch:g} mm plus the reference's "
                f"tensioner slack {1000 * REFERENCE_SLACK:.0f} mm"
            )
        self.incline_length = length
        self.rise = 2.0 * rt * (1.0 - math.cos(a)) + self.incline_length * math.sin(a)
        perimeter = 2.0 * (self.incline_length + fixed)
        slack = (perimeter - self.n_links * self.pitch) / 2.0
        travel = closing_travel(lt)
        if not -travel < slack < travel:
            lo, hi = closing_links(perimeter, self.pitch, lt)
            k = p.links_per_step
            whole = [n for n in range(lo, hi + 1) if n % k == 0]
            steps = (
                f" ({whole[0]} to {whole[-1]} in whole {'pallets' if p.is_walk else 'steps'} of {k})" if whole else ""
            )
            if p.is_walk:
                # the loop's length moves 2 / cos(a) m a metre of the walk's length in plan
                g_lo = p.length - (slack + travel) * math.cos(a)
                g_hi = p.length - (slack - travel) * math.cos(a)
                where, span = f"'geometry.length' = {p.length:g} m", f"a length of {max(g_lo, 0):.2f} to {g_hi:.2f} m"
                check = "chain.n_links and geometry.length"
            else:
                # the loop's length moves 2 / sin(a) m a metre of rise
                g_lo = self.rise - (slack + travel) * math.sin(a)
                g_hi = self.rise - (slack - travel) * math.sin(a)
                where, span = f"'geometry.rise' = {p.rise:g} m", f"a rise of {max(g_lo, 0):.2f} to {g_hi:.2f} m"
                check = "chain.n_links and geometry.rise"
            raise SceneError(
                f"{p.source}: 'chain.n_links' = {self.n_links} links of {1000 * self.pitch:g} mm "
                f"({self.n_links * self.pitch:.3f} m) cannot close on the loop of {where} at "
                f"'geometry.incline_deg' = {a_deg:g} ({perimeter:.3f} m): the tensioner would have to move "
                f"{1000 * slack:.0f} mm, beyond its travel of +-{1000 * travel:.0f} mm; the link counts that close "
                f"on this {'length' if p.is_walk else 'rise'} are {lo} to {hi}{steps}, and {self.n_links} links "
                f"close on {span}: check {check} against the drawings"
            )
        self.slack = slack


def geometry_note(profile) -> str | None:
    """What the scene assumed of a profile that states no geometry (``chain.n_links`` alone): an escalator of
    the common 30 deg incline, whose rise follows from the count; None where the profile states it."""
    if profile.geometry_given:
        return None
    f = _Filled(profile)
    return (
        f"{profile.source} states no geometry: built as an escalator of the common {DEFAULT_INCLINE_DEG:g} deg "
        f"incline whose rise ({f.rise:.2f} m) follows from chain.n_links = {f.n_links}; give geometry.rise and "
        "geometry.incline_deg (an escalator) or geometry.length and geometry.incline_deg (a moving walk)"
    )


def running_resistance(f) -> tuple[float, float, str]:
    """``(coefficient, no-load drive power [W], where it came from)`` of the scene's running resistance for the
    filled numbers ``f`` of a profile: mu = P / (g M v) for the chain and steps' mass M = n_links x roller_mass at
    the rated speed v, P the profile's ``drive.no_load_power``, else :data:`TYPICAL_RESISTANCE_N_PER_M` times the
    loop's length times v.  A power the chain's weight cannot carry (mu >= 1) is a SceneError naming the key."""
    p = f.profile
    mass = f.n_links * f.roller_mass
    v = abs(float(p.speed))
    if p.no_load_power is not None:
        power = float(p.no_load_power)
        src = f"drive.no_load_power {power:g} W at {v:g} m/s"
    else:  # what a firm without a figure of its own may state
        power = TYPICAL_RESISTANCE_N_PER_M * f.n_links * f.pitch * v
        src = (
            f"filled: typical {TYPICAL_RESISTANCE_N_PER_M:.1f} N per metre of loop (TfL: 2 kW of friction on a 15 m "
            f"escalator at 0.75 m/s), {power:.0f} W at {v:g} m/s; drive.no_load_power states the unit's"
        )
    mu = power / (G * mass * v)
    if not mu < 1.0:
        raise SceneError(
            f"{p.source}: 'drive.no_load_power' = {power:g} W at {v:g} m/s is more than the weight of the chain and "
            f"steps ({mass:.0f} kg: {MASS_PER_METRE:g} kg per metre of chain) can resist ({G * mass * v:.0f} W); give "
            "the power the drive gives the chain (the motor's no-load input less its and the gearbox's losses), in W"
        )
    return mu, power, src


def drive_gains(f) -> tuple[float, float]:
    """``(kp [N m s], ki [N m])`` of the scene's PI speed controller: the closed loop of the sprocket and the chain
    (inertia J = M R^2 + J_sprocket at the pitch radius R) at :data:`DRIVE_BANDWIDTH` with :data:`DRIVE_DAMPING`:
    kp = 2 zeta w J, ki = w^2 J.  Stiff enough to hold the rated speed against the running resistance (no steady
    error: the integral carries it), soft enough for the solver's usual steps."""
    inertia = f.n_links * f.roller_mass * f.pitch_radius**2 + f.inertia
    w, zeta = DRIVE_BANDWIDTH, DRIVE_DAMPING
    return float(f"{2.0 * zeta * w * inertia:.4g}"), float(f"{w * w * inertia:.4g}")


def link_count(profile) -> tuple[int, str]:
    """``(links, where the count came from)`` of the profile's scene: ``chain.n_links`` as given, else the
    whole steps vibkit derives from ``geometry.rise`` and ``geometry.incline_deg``; a SceneError where the
    count cannot close."""
    f = _Filled(profile)
    return int(f.n_links), f.links_src


def closing_travel(tensioner_length: float) -> float:
    """How far the tensioner carriage can move either way for the chain to close [m]: the guide's
    monotonic travel (:data:`vibkit.model.params.TRAVEL`) less the closure scan's end cells."""
    return TRAVEL * tensioner_length * (1.0 - 2.0 / 80.0)


def closing_links(perimeter: float, pitch: float, tensioner_length: float) -> tuple[int, int]:
    """The fewest and most links of ``pitch`` that close on a loop of ``perimeter`` [m] within the tensioner's
    travel (the carriage moves half the difference)."""
    travel = closing_travel(tensioner_length)
    return math.floor((perimeter - 2.0 * travel) / pitch) + 1, math.ceil((perimeter + 2.0 * travel) / pitch) - 1


def scene_text(profile, analysis: str = "forward", duration: float | None = None) -> str:
    """The TOML scene of ``profile`` for ``analysis`` ("forward" or "inverse"), with comments that
    say where each value came from."""
    if analysis not in ("forward", "inverse"):
        raise ValueError(f"analysis must be 'forward' or 'inverse', got {analysis!r}")
    p = profile
    f = _Filled(p)
    dur = DEFAULT_DURATION[analysis] if duration is None else float(duration)
    if not dur > 0:
        raise ValueError(f"duration must be positive, got {duration!r}")
    name = "".join(c if c.isalnum() or c in "-_" else "-" for c in p.unit).strip("-") or "escalator"
    # the user's own line where the profile has one (the scene's keys say the rest), else the facts
    facts = (
        f"{p.speed:g} m/s{' down' if p.direction == 'down' else ''}, {1000 * p.nominal_pitch:g} mm pitch, "
        f"{p.links_per_step} links per {'pallet' if p.is_walk else 'step'}"
    )
    desc = f"{p.name}: {p.description or facts}"
    pre = p.tensioner_preload
    lines = [
        f"# The scene of {p.kind} {p.unit}, built by vibkit from the profile {p.source}.",
        "# From the profile: unit, speed, nominal pitch, links per step, sprocket teeth"
        + (", number of links" if p.n_links is not None else "")
        + (", rise" if p.rise is not None else "")
        + (", length between the heads" if p.length is not None else "")
        + (", incline" if p.incline_deg is not None else "")
        + (", roller radius" if p.roller_radius is not None else "")
        + (", tensioner preload" if pre is not None else "")
        + ".",
        "# Filled from the study's reference escalator (vibkit.model.profile_scene explains each rule):",
        f"# tooth size and {'' if p.roller_radius is not None else 'roller radius '}scaled with the pitch "
        f"(x {f.scale:.4f}), {MASS_PER_METRE:g} kg per metre of chain and steps,",
        "# sprocket mass and inertia scaled with its pitch radius, landings, transitions and tensioner runs,",
        "# contact stiffness and speed controller"
        + (", tensioner preload (so that no link goes into compression)." if pre is None else "."),
        *([f"# NOTE: {note}."] if (note := geometry_note(p)) else []),
        "[scene]",
        f'name = "{name}"',
        f'analysis = "{analysis}"',
        f"description = {_toml_str(desc)}",
        "",
        "[guide]",
        f"tensioner_length = {_fmt(_RG.tensioner_length)}   # reference",
        f"lower_landing = {_fmt(_RG.lower_landing)}      # reference",
        f"upper_landing = {_fmt(_RG.upper_landing)}      # reference",
        f"transition_radius = {_fmt(_RG.transition_radius)}  # reference",
        f"incline_angle_deg = {_fmt(f.incline_deg)}  # "
        + ("geometry.incline_deg" if p.incline_deg is not None else "filled: 30 deg, the common incline")
        + (" (a level walk: the transitions turn nothing)" if p.is_walk and f.incline_deg == 0 else ""),
        f"incline_length = {f.incline_length:.6f}  # {f.length_src} (rise {f.rise:.3f} m)",
        'head_radius = "sprocket"  # the heads turn on the sprocket\'s pitch circle',
        "",
        "[chain]",
        f"link_pitch = {_fmt(f.pitch)}  # chain.nominal_pitch",
        f"roller_radius = {f.roller_radius:.6g}  # {f.roller_src}",
        f"roller_mass = {f.roller_mass:.6g}  # filled: {MASS_PER_METRE:g} kg/m of chain and steps x pitch",
        f"n_rollers = {f.n_links}  # {f.links_src}",
        f"links_per_step = {p.links_per_step}  # chain.links_per_step",
        "",
        "[sprocket]",
        f"teeth = {f.teeth}  # drive.teeth",
        f"base_width = {f.base_width:.6g}  # filled: reference 60 mm x pitch / 133.33 mm",
        f"tip_width = {f.tip_width:.6g}  # filled: reference 40 mm x pitch / 133.33 mm",
        f"tooth_height = {f.tooth_height:.6g}  # filled: reference 70 mm x pitch / 133.33 mm",
        f"mass = {f.sprocket_mass:.6g}  # filled: reference 250.62 kg x (R / 0.5954 m)^2",
        f"inertia = {f.inertia:.6g}  # filled: reference 43.78 kg m^2 x (R / 0.5954 m)^4",
        "",
    ]
    driven = analysis == "forward" and p.no_load_power != 0
    mu, power, mu_src = running_resistance(f) if driven else (0.0, 0.0, "")
    preload = pre if pre is not None else default_preload(f, mu)
    pre_src = (
        "tensioner.preload"
        if pre is not None
        else f"filled: twice the weight of the steepest strand's chain, at least {MIN_PRELOAD:g} N"
        + (", plus what the running resistance takes from the slack strand" if driven else "")
    )
    if analysis == "forward":
        if driven:  # the stated (else a typical) running resistance, a PI drive started in steady running
            kp, ki = drive_gains(f)
            torque = steady_torque(f, power)
            drive = [
                f"motor = {{ kp = {kp!r}, ki = {ki!r}, speed = {_fmt(p.set_speed)}, initial_torque = {torque:.6g} }}"
                f"  # drive.speed{_down(p)}: the step speed on the straight; PI gains from the unit's inertia; "
                "started carrying the running resistance (no-load power / sprocket speed)",
                f"rolling_resistance = {{ coefficient = {mu:.6g} }}  # {mu_src}",
            ]
        else:
            drive = [
                f"motor = {{ kp = 600.0, speed = {_fmt(p.set_speed)} }}  # drive.speed{_down(p)}: the step speed on "
                "the straight",
                "# no running resistance (drive.no_load_power = 0): the chain coasts at speed",
            ]
        lines += [
            "[run]",
            f"duration = {dur:g}  # [s]",
            f"output_step = {OUTPUT_STEP:g}  # [s]",
            "start = 0.0",
            f"initial_speed = {_fmt(p.set_speed)}  # started at the rated speed{_down(p)}: steady running from the start",
            "",
            "[effects]",
            "gravity = true",
            "contact = { stiffness = 1.0e6, exponent = 1.5, damping = 0.3 }  # reference",
            *drive,
            f"tensioner = {{ preload = {preload:.6g} }}  # {pre_src} [N]",
            "",
            "[solver]",
            'method = "dopri5"',
            "",
            "[outputs]",
            'variables = ["delta", "sprocket_speed", "motor_torque", "chain_speed", "link_tension",'
            ' "closure_residual", "tensioner_displacement", "accel_step"]',
        ]
        step = p.sensor.step if p.sensor is not None and p.sensor.kind == "step" else None
        n_steps = f.n_links // p.links_per_step
        lines.append(f"step_accelerometer = {step if step and step <= n_steps else min(3, n_steps)}")
    else:
        lines += [
            "[motion]",
            f"speed = {_fmt(p.set_speed)}  # drive.speed{_down(p)}: the step speed on the straight",
            f"duration = {dur:g}  # [s]",
            f"step = {OUTPUT_STEP:g}  # [s]",
            "start = 0.0",
            "",
            "[effects]",
            "gravity = true",
            f"tensioner = {{ preload = {preload:.6g} }}  # {pre_src} [N]",
            "",
            "[outputs]",
            'variables = ["delta", "link_tension", "drive_force", "closure_residual", "chain_speed", "energy"]',
        ]
    return "\n".join(lines) + "\n"


def _down(p) -> str:
    """The comment's note where the steps travel down (the speed negative)."""
    return " (negative: drive.direction = down)" if p.direction == "down" else ""


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


#: the least preload a profile's scene gets [N]: the reference escalator's (twice the weight of its 3 m rise's
#: strand along the slope, 3.06 kN); a level moving walk's strands weigh nothing along the guide, and its
#: tensioner's spring still holds the chain taut (a real one gives several kN)
MIN_PRELOAD = 3060.0


def default_preload(f, mu: float = 0.0) -> float:
    """A tensioner preload that keeps every link in tension [N], for a running resistance ``mu`` (0: none).

    The return strand hangs from the sprocket: without a preload its links below the incline's top
    carry the weight of the chain below them as compression where the guide pushes them down hill.
    Twice the weight of one strand's incline (steps and chain, along the slope) keeps every link in
    tension with a margin; a real tensioner's spring gives several kN. Never less than
    :data:`MIN_PRELOAD` (a level or gently inclined moving walk).

    A driven chain (``mu`` > 0) keeps that margin where its tension is least.  The carriage holds the two
    strands at the lower head, T_in + T_out = preload, and the head's rollers' resistance makes T_out = T_in +
    R_head; walking the slack strand (the one that leaves the sprocket, whichever way the unit runs: it always
    runs down hill to the tensioner) back up from the lower head, its tension falls by mu m g per metre and rises
    by m g per metre climbed, so it is least where mu m g s less m g z(s) is largest
    (:func:`slack_deficit`).  The preload adds twice that and R_head: on an escalator a few hundred N (its
    landings and tensioner run, where nothing climbs), on a level walk the whole strand's resistance.
    """
    a = math.radians(f.incline_deg)
    strand = MASS_PER_METRE * f.incline_length * 9.81 * math.sin(a)
    base = max(round(2.0 * strand, -1), MIN_PRELOAD)
    if not mu > 0:
        return base
    head = mu * MASS_PER_METRE * G * math.pi * f.pitch_radius
    return base + 10.0 * math.ceil((2.0 * slack_deficit(f, mu) + head) / 10.0)


def slack_deficit(f, mu: float) -> float:
    """The most tension [N] the running resistance ``mu`` takes from the slack strand, walked from the lower
    head's entry (the tensioner run, lower landing, transition, incline, transition and upper landing, to the
    sprocket) less what its climb gives back: max over s of m g (mu s - z(s)), m the chain and steps per metre,
    s the length walked and z the height climbed (0 where the strand does not climb at all)."""
    a = math.radians(f.incline_deg)
    rt = _RG.transition_radius
    # the slack strand as pieces (length, angle at its start, angle at its end), climbing at the angle
    pieces = [
        (_RG.tensioner_length + _RG.lower_landing, 0.0, 0.0),
        (rt * a, 0.0, a),
        (f.incline_length, a, a),
        (rt * a, a, 0.0),
        (_RG.upper_landing, 0.0, 0.0),
    ]
    s_end, z_end, worst = 0.0, 0.0, 0.0
    for length, a0, a1 in pieces:
        u = np.linspace(0.0, 1.0, 401)
        ang = a0 + (a1 - a0) * u
        ds = length / (u.size - 1)
        z = z_end + np.concatenate(([0.0], np.cumsum(0.5 * (np.sin(ang[1:]) + np.sin(ang[:-1])) * ds)))
        s = s_end + length * u
        worst = max(worst, float(np.max(mu * s - z)))
        s_end, z_end = s[-1], z[-1]
    return MASS_PER_METRE * G * worst


def steady_torque(f, power: float) -> float:
    """The drive's torque [N m] in steady running at the no-load ``power`` [W]: power / sprocket speed, the
    sprocket turning 2 pi v / (Z L) at the chain speed v (:meth:`vibkit.model.escalator.EscalatorModel.sprocket_speed`)."""
    v = abs(float(f.profile.speed))
    return power * f.teeth * f.pitch / (2.0 * math.pi * v)


def profile_scene(profile, analysis: str = "forward", duration: float | None = None) -> Scene:
    """The validated scene of ``profile`` (see :func:`scene_text`), refused where it cannot run."""
    text = scene_text(profile, analysis, duration)
    src = f"{profile.source} (scene built from the profile)"
    try:
        scene = parse_scene(text, src)
    except SceneError as exc:
        raise SceneError(f"{profile.source}: the scene built from the profile is not valid: {exc}") from None
    check_fits(scene, profile)
    return scene


def check_closes(model, scene, profile) -> None:
    """Refuse a scene whose chain does not close on its guide at every place round the loop (the closure is
    solved with roller 1 at eight places), naming the profile's keys and the link counts that close."""
    from .chain import ClosureError

    p0 = model.chain.guide.p0
    try:
        for s0 in np.linspace(0.0, p0, 8, endpoint=False):
            model.chain.configure(float(s0))
    except ClosureError:
        lo, hi = closing_links(p0, scene.chain.link_pitch, scene.guide.tensioner_length)
        keys = "chain.n_links" + (" and geometry.rise" if profile.rise is not None else "")
        raise SceneError(
            f"{profile.source}: the chain of {scene.chain.n_rollers} links of {1000 * scene.chain.link_pitch:g} mm "
            f"does not close on the unit's guide ({p0:.3f} m round) within the tensioner's travel: the link counts "
            f"that close on it are {lo} to {hi}; check {keys} against the drawings"
        ) from None


def check_fits(scene, profile) -> None:
    """Refuse a scene whose rollers sit inside the teeth at t = 0, or whose heads are not the sprocket's."""
    from .escalator import EscalatorModel

    src = profile.source
    rp = scene.sprocket.pitch_radius(scene.chain.link_pitch)
    if not math.isclose(scene.guide.head_radius, rp, rel_tol=1e-12):
        raise SceneError(
            f"{src}: the head radius {scene.guide.head_radius:g} m is not the sprocket's pitch radius {rp:.6g} m "
            "(drive.teeth and chain.nominal_pitch set it)"
        )
    start = scene.run.start if scene.analysis == "forward" else scene.motion.start
    model = EscalatorModel(scene)
    check_closes(model, scene, profile)
    worst = model.initial_indentation(start)
    if worst > 1e-6 * scene.chain.link_pitch:
        key = "chain.roller_radius" if profile.roller_radius is not None else "chain.nominal_pitch"
        raise SceneError(
            f"{src}: the rollers ({1000 * scene.chain.roller_radius:.4g} mm radius) sit {1000 * worst:.3g} mm "
            f"inside the sprocket's teeth at the start (teeth cut for a {1000 * scene.chain.link_pitch:g} mm pitch, "
            f"{scene.sprocket.teeth} teeth): change {key}"
            + (
                f" (the standard proportion is {1000 * _RC.roller_radius * scene.chain.link_pitch / REFERENCE_PITCH:.3g} mm)"
                if profile.roller_radius is not None
                else ""
            )
        )
