"""
An escalator's chain path from its profile
==========================================

An escalator profile (``--escalator FILE``) says what a maintenance firm knows of a unit: rise,
incline, speed, chain pitch, sprocket. ``vibkit scene PROFILE`` turns it into a scene, the model's
description of the escalator: here the guides the step chain runs on for the example fleet's escalators
(E07 given by its link count, E12 and E21 by rise and incline), drawn beside the study's escalator
(``sim/thesis-forward.toml``) the model was built on.
"""

import matplotlib.pyplot as plt
import numpy as np

import vibkit
import vibkit.datasets
import vibkit.scenes
from vibkit.model.guide import Guide
from vibkit.model.profile import load_profile
from vibkit.model.profile_scene import profile_scene

PROFILES = vibkit.datasets.path("fleet-example/escalators")
scenes = {"study's escalator (sim/thesis-forward.toml)": vibkit.load_scene(vibkit.scenes.path("thesis-forward"))}
for unit in ("E07", "E12", "E21"):
    profile = load_profile(PROFILES / f"{unit}.toml")
    scenes[f"{unit}: {profile.description or 'profile'}"] = profile_scene(profile)

fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
for label, scene in scenes.items():
    guide = Guide(scene.guide)
    s = np.linspace(0.0, guide.perimeter(), 2000)
    xz = guide.position(s)
    ax.plot(
        xz[:, 0], xz[:, 1], lw=1.2, label=f"{label}: {scene.chain.n_rollers} rollers, loop {guide.perimeter():.2f} m"
    )
ax.set_aspect("equal")
ax.set_xlabel("x [m]")
ax.set_ylabel("z [m]")
ax.legend(loc="upper left", fontsize=8)
plt.show()
