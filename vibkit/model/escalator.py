"""The escalator model assembled from a scene: guide, chain, sprocket and the effects asked for."""

from __future__ import annotations

import math

import numpy as np

from .chain import Chain
from .guide import LEN0, S0, SEGMENT_NAMES, Guide
from .sprocket import contact_kernel, local_corners, mesh_phase, tooth_geometry, tooth_table

__all__ = ["EscalatorModel"]


class EscalatorModel:
    """Guide + chain + sprocket of one scene, with the derived quantities the analyses share.

    Parameters
    ----------
    scene : Scene
    """

    def __init__(self, scene):
        self.scene = scene
        self.guide = Guide(scene.guide)
        self.chain = Chain(self.guide, scene.chain)
        self.sprocket = scene.sprocket
        self.n = scene.chain.n_rollers
        self.pitch = scene.chain.link_pitch
        #: the pitch the sprocket's teeth are cut for (the chain's own unless the scene says otherwise) [m]
        self.sprocket_pitch = self.sprocket.cut_pitch(self.pitch)
        self.mass = scene.chain.masses()
        self.radii = scene.chain.radii()
        # the chain's mean link length: the chain advances Z of them per sprocket turn (worn links included)
        pitches = scene.chain.pitches()
        self.mean_pitch = float(pitches.mean()) if bool(np.any(pitches != self.pitch)) else self.pitch
        self.centre = np.array(scene.guide.sprocket_centre)
        self.geometry = tooth_geometry(self.sprocket, self.sprocket_pitch, scene.chain.roller_radius)
        self.corners_local = local_corners(self.sprocket, self.sprocket_pitch, scene.chain.roller_radius)
        #: what the contact kernel needs of the teeth (:func:`vibkit.model.sprocket.tooth_table`)
        self.teeth = tooth_table(
            self.corners_local,
            self.geometry["root_radius"],
            self.geometry["tooth_pitch"],
            self.sprocket.teeth,
            float(np.max(self.radii)),
        )

    def links_passed(self, s0_from: float, s0_to: float, travel: float) -> float:
        """Links that pass a fixed point (the middle of the incline's top run) while roller 1 moves from
        undeformed coordinate ``s0_from`` to ``s0_to`` [m], about ``travel`` metres of chain. (Fractional.)

        Exact where the chain's speed varies within a loop: roller 1's own coordinate does not count links (a
        link on a head or the tensioner's telescopic run spans more of it than one on a straight; over half a
        loop that is 0.3 % on the study's escalator). The rollers on either side of the point are on one
        straight, where the undeformed coordinate is the arc length. ``travel`` (to within half a loop) fixes
        the whole loops."""
        tab, p0, n = self.guide.table, self.guide.p0, self.n
        k = SEGMENT_NAMES.index("incline, top run")
        place = tab[k, S0] + 0.5 * tab[k, LEN0]

        def index_at(s):
            # rollers are numbered along the motion: the one just behind the point, plus the share of its link
            s0 = self.chain.configure(float(s)).s0
            d = np.mod(place - s0, p0)
            j = int(np.argmin(d))
            gap = np.mod((s0[j + 1] if j + 1 < n else s0[0] + p0) - s0[j], p0)
            return j + d[j] / gap

        within = np.mod(index_at(s0_from) - index_at(s0_to), n)
        return float(within + n * round((n * travel / p0 - within) / n))

    @property
    def pitch_radius(self) -> float:
        return self.geometry["pitch_radius"]

    def sprocket_speed(self, chain_speed: float) -> float:
        """Sprocket speed thetadot [rad/s] that moves the chain at ``chain_speed`` [m/s] on the straight.

        The chain advances Z link pitches per turn of a Z-tooth sprocket, so its mean speed on the
        straight is Z L omega / (2 pi) (not the pitch circle's omega R^P, 0.21 % faster at Z = 28):
        thetadot = -2 pi v / (Z L), negative because the sprocket turns clockwise while the steps go up.
        L is the chain's mean link length (a worn link moves the chain further per tooth, not the teeth).
        The link-pass frequency is then v / L = Z |thetadot| / (2 pi) exactly.
        """
        return -2.0 * math.pi * chain_speed / (self.sprocket.teeth * self.mean_pitch)

    def link_pass_frequency(self, speed: float) -> float:
        """f_link = |v| / L_link, L_link the chain's mean link length. [Hz]"""
        return abs(speed) / self.mean_pitch

    def meshed_angle(self, conf) -> float:
        """Sprocket angle that meshes with configuration ``conf`` (rollers midway between teeth). [rad]"""
        return mesh_phase(conf.position, self.centre, self.sprocket, self.pitch)

    def initial_indentation(self, start: float) -> float:
        """Deepest roller-tooth overlap [m] with roller 1 at ``start`` [m of undeformed guide] and the
        sprocket meshed (:meth:`meshed_angle`): 0 when every roller clears the teeth, as a run must start."""
        conf = self.chain.configure(float(start))
        return self.static_contact(conf, self.meshed_angle(conf))[1]

    def static_contact(self, conf, theta: float, stiffness: float = 1.0, exponent: float = 1.0) -> tuple[float, float]:
        """``(torque on the sprocket [N m], deepest roller-tooth overlap [m])`` of configuration ``conf`` at rest
        with the sprocket at angle ``theta``, the contact of ``stiffness`` and ``exponent`` without damping."""
        n, z = self.n, self.sprocket.teeth
        pos = np.ascontiguousarray(conf.position, dtype=float)
        zeros = np.zeros(n)
        out = contact_kernel(
            pos[:, 0].copy(), pos[:, 1].copy(), zeros, zeros, np.arange(n, dtype=np.int64), n, theta, 0.0,
            self.centre[0], self.centre[1], self.teeth, self.radii, stiffness, exponent, 0.0, np.zeros(n), np.zeros(n),
            np.zeros(z), np.zeros(z), False,
        )  # fmt: skip
        return float(out[0]), float(out[2])

    def loaded_angle(self, conf, theta: float, torque: float, stiffness: float, exponent: float) -> float:
        """The sprocket angle [rad] reached from the meshed ``theta`` turning in the sense of ``torque`` [N m]
        until the teeth pressed into the rollers of ``conf`` (at rest, :meth:`static_contact`) carry it: the first
        angle that does, in steps of a 64th of half a tooth pitch, then bisection to 1e-12 rad; ``theta`` where
        they cannot within half a tooth pitch. A run started in steady running starts there."""
        sense = math.copysign(1.0, torque)

        def carried(x):  # the teeth's torque against the motor's
            return -sense * self.static_contact(conf, theta + sense * x, stiffness, exponent)[0]

        steps = np.linspace(0.0, math.pi / self.sprocket.teeth, 65)
        over = [x for x in steps[1:] if carried(x) >= abs(torque)]
        if not over:
            return theta
        lo, hi = over[0] - steps[1], over[0]
        while hi - lo > 1e-12:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if carried(mid) < abs(torque) else (lo, mid)
        return theta + sense * lo

    def step_rollers(self, step: int) -> np.ndarray:
        """0-based indices of the rollers (``links_per_step``: 3, or 4) of 1-based step ``step``; the
        middle one (index 1 of 3 or 4) is where a step is placed."""
        k = self.scene.chain.links_per_step
        return np.arange(k * (step - 1), k * step) % self.n

    def gravity_forces(self, g: float) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(self.n), -self.mass * g

    def place(self, name: str) -> float:
        """Undeformed-guide coordinate of a named place of the guide. [m]

        ``"lower_landing"`` and ``"upper_landing"``: the middle of the landing's top run, where
        passengers step on and off (model.md section 7).
        """
        seg = {"lower_landing": 1, "upper_landing": 5}[name]
        tab = self.guide.table
        return float(tab[seg, 0] + 0.5 * tab[seg, 1])

    def passenger_schedule(self, opts, start: float):
        """Where or when each passenger is aboard: (by_place, board, alight) arrays.

        ``opts`` are the passengers' options (:class:`vibkit.model.schema.PassengersOptions`).

        By place (the default): board and alight are the unwrapped undeformed coordinates that the
        middle roller of the passenger's step passes when it reaches the boarding and alighting
        places on the ride that is under way at ``start`` or the first one after it [m]; a step
        already between the two at the start carries its passenger from t = 0. By time: the times
        given in the scene [s].
        """
        board, alight = list(opts.board), list(opts.alight)
        if not isinstance(board[0], str):
            return False, np.asarray(board, dtype=float), np.asarray(alight, dtype=float)
        conf = self.chain.configure(float(start))
        p0 = self.guide.p0
        b_abs, a_abs = [], []
        for step, b, a in zip(opts.step, board, alight):
            u0 = float(conf.s0[int(self.step_rollers(step)[1])])
            sb, sa = self.place(b), self.place(a)
            if sa <= sb:
                sa += p0
            j = math.floor((u0 - sa) / p0) + 1  # the smallest ride whose alighting lies ahead
            b_abs.append(sb + j * p0)
            a_abs.append(sa + j * p0)
        return True, np.asarray(b_abs), np.asarray(a_abs)

    def passenger_forces(self, opts, t: float, g: float, fz: np.ndarray, *, s0=None, schedule=None) -> None:
        """Add each passenger's weight, shared by the rollers of its step, while aboard.

        ``schedule`` is :meth:`passenger_schedule`'s result; by place, ``s0`` holds the rollers'
        unwrapped undeformed coordinates (a :class:`~vibkit.model.chain.Configuration`'s ``s0``).
        """
        by_place, board, alight = schedule if schedule is not None else (False, opts.board, opts.alight)
        for m, step, b, a in zip(opts.mass, opts.step, board, alight):
            rollers = self.step_rollers(step)
            where = s0[rollers[1]] if by_place else t
            if b <= where < a:
                fz[rollers] -= m * g / rollers.size

    def wrap_angle(self, theta: float) -> float:
        return math.remainder(theta, 2 * math.pi)
