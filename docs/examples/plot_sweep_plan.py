"""
What a sweep will run
=====================

``vibkit sweep`` (:func:`vibkit.sweep`) runs one scene over a grid of its keys, or over random draws
within ranges (``--samples N --seed S``). Before any run starts, :func:`vibkit.sweep.plan_sweep` checks
and expands the definition: every key against what the scene's analysis reads, the values, and the size
of the result against the budget. Here the guide's sweep of link pitch and contact stiffness, planned as
a grid of 27 runs and as 27 random draws over the same ranges; each point is one simulation.
"""

import matplotlib.pyplot as plt

import vibkit.scenes
from vibkit.sweep import plan_sweep

SCENE = vibkit.scenes.path("thesis-forward")
grid = plan_sweep(
    SCENE, {"chain.link_pitch": "0.1333:0.1373:9", "effects.contact.stiffness": [1e5, 1e6, 1e7]}, duration=10
)
draws = plan_sweep(
    SCENE,
    {"chain.link_pitch": "0.1333:0.1373", "effects.contact.stiffness": "1e5:1e7"},
    samples=27,
    seed=1,
    duration=10,
)
print("grid:", grid.dims, grid.shape, "| draws:", draws.dims, draws.shape)

fig, axes = plt.subplots(1, 2, figsize=(9, 3.5), sharey=True, layout="constrained")
for ax, plan, title in ((axes[0], grid, "grid (--vary KEY=LO:HI:N)"), (axes[1], draws, "draws (--samples 27)")):
    pitch = [p["chain.link_pitch"] * 1e3 for p in plan.points]
    stiffness = [p["effects.contact.stiffness"] for p in plan.points]
    ax.scatter(pitch, stiffness, s=18)
    ax.set_yscale("log")
    ax.set_xlabel("chain.link_pitch [mm]")
    ax.set_title(title)
axes[0].set_ylabel("effects.contact.stiffness [N/m]")
plt.show()
