"""The escalator model assembled from a scene: guide, chain, sprocket and the effects asked for."""

from __future__ import annotations

import math

import numpy as np

from .chain import Chain
from .guide import Guide
from .sprocket import local_corners, mesh_phase, tooth_geometry

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
        self.mass = np.full(self.n, scene.chain.roller_mass)
        self.centre = np.array(scene.guide.sprocket_centre)
        self.geometry = tooth_geometry(self.sprocket, self.pitch, scene.chain.roller_radius)
        self.corners_local = local_corners(self.sprocket, self.pitch, scene.chain.roller_radius)

    @property
    def pitch_radius(self) -> float:
        return self.geometry["pitch_radius"]

    def link_pass_frequency(self, speed: float) -> float:
        """f_link = |v| / L_link. [Hz]"""
        return abs(speed) / self.pitch

    def meshed_angle(self, conf) -> float:
        """Sprocket angle that meshes with configuration ``conf`` (rollers midway between teeth). [rad]"""
        return mesh_phase(conf.position, self.centre, self.sprocket, self.pitch)

    def step_rollers(self, step: int) -> np.ndarray:
        """0-based indices of the three rollers of 1-based step ``step``."""
        return np.arange(3 * (step - 1), 3 * step) % self.n

    def gravity_forces(self, g: float) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(self.n), -self.mass * g

    def passenger_forces(self, opts: dict, t: float, g: float, fz: np.ndarray) -> None:
        """Add each passenger's weight, shared by the three rollers of its step, while aboard."""
        for m, step, board, alight in zip(opts["mass"], opts["step"], opts["board"], opts["alight"]):
            if board <= t < alight:
                fz[self.step_rollers(step)] -= m * g / 3.0

    def wrap_angle(self, theta: float) -> float:
        return math.remainder(theta, 2 * math.pi)
